// The reports' axes (svg_plot.hpp): ticks at 1, 2 or 5 times a power of ten, their labels,
// markers, labelled bands and the legend column.
#include "selfsense/report/svg_plot.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

namespace selfsense::report {
namespace {

std::size_t count(std::string_view text, std::string_view what) {
  std::size_t n = 0;
  for (std::size_t pos = text.find(what); pos != std::string_view::npos;
       pos = text.find(what, pos + what.size())) {
    ++n;
  }
  return n;
}

TEST(AxisTicks, StepsAreOneTwoOrFiveTimesAPowerOfTen) {
  EXPECT_DOUBLE_EQ(nice_step(10.0, 5), 2.0);
  EXPECT_DOUBLE_EQ(nice_step(7.7, 5), 2.0);   // raw 1.54
  EXPECT_DOUBLE_EQ(nice_step(4.0, 5), 1.0);   // raw 0.8
  EXPECT_DOUBLE_EQ(nice_step(12.0, 5), 5.0);  // raw 2.4
  EXPECT_DOUBLE_EQ(nice_step(30.0, 5), 10.0);
  EXPECT_DOUBLE_EQ(nice_step(5.0, 5), 1.0);  // exactly five steps: no rounding up
  EXPECT_NEAR(nice_step(9e-4, 5), 2e-4, 1e-18);
  EXPECT_NEAR(nice_step(3e6, 5), 1e6, 1e-6);
  for (const double span : {1e-9, 3.3e-5, 0.77, 1.0, 42.0, 9.9e7}) {
    const double step = nice_step(span, 5);
    const double mantissa = step / std::pow(10.0, std::floor(std::log10(step) + 1e-9));
    EXPECT_TRUE(std::abs(mantissa - 1.0) < 1e-9 || std::abs(mantissa - 2.0) < 1e-9 ||
                std::abs(mantissa - 5.0) < 1e-9)
        << span << ": step " << step;
    EXPECT_GE(step * 5.0 * (1.0 + 1e-9), span) << span;
    EXPECT_LT(step, span) << span;
  }
  EXPECT_EQ(nice_step(0.0, 5), 0.0);
  EXPECT_EQ(nice_step(-1.0, 5), 0.0);
  EXPECT_EQ(nice_step(1.0, 0), 0.0);
  EXPECT_EQ(nice_step(std::numeric_limits<double>::infinity(), 5), 0.0);
}

TEST(AxisTicks, TicksAreTheStepsMultiplesInsideTheRange) {
  EXPECT_EQ(nice_ticks(-0.35, 7.35), (std::vector<double>{0.0, 2.0, 4.0, 6.0}));
  EXPECT_EQ(nice_ticks(0.0, 10.0), (std::vector<double>{0.0, 2.0, 4.0, 6.0, 8.0, 10.0}));
  // A time axis of a recording 10.2 .. 14.1 s: every 1 s (0.5 s would be 8 intervals); of
  // 10.2 .. 12.1 s every 0.5 s.
  EXPECT_EQ(nice_ticks(10.2, 14.1), (std::vector<double>{11.0, 12.0, 13.0, 14.0}));
  EXPECT_EQ(nice_ticks(10.2, 12.1), (std::vector<double>{10.5, 11.0, 11.5, 12.0}));
  // Strain in 1e-6 over a staircase, stress in MPa (negative: compression).
  EXPECT_EQ(nice_ticks(105.0, 1095.0), (std::vector<double>{200.0, 400.0, 600.0, 800.0, 1000.0}));
  EXPECT_EQ(nice_ticks(-8.3, -4.7), (std::vector<double>{-8.0, -7.0, -6.0, -5.0}));
  // Zero is exactly zero, not -1e-17.
  const std::vector<double> z = nice_ticks(-0.3, 0.3);
  ASSERT_EQ(z.size(), 3U);
  EXPECT_EQ(z[1], 0.0);
  EXPECT_FALSE(std::signbit(z[1]));
  EXPECT_TRUE(nice_ticks(1.0, 1.0).empty());
  EXPECT_TRUE(nice_ticks(2.0, 1.0).empty());
  EXPECT_TRUE(nice_ticks(0.0, std::numeric_limits<double>::quiet_NaN()).empty());
  EXPECT_LE(nice_ticks(1.7e18, 1.7e18 + 4096.0).size(), 12U);
}

TEST(AxisTicks, LabelsHaveTheDecimalsOfTheStep) {
  EXPECT_EQ(format_tick(10.5, 0.5), "10.5");
  EXPECT_EQ(format_tick(11.0, 0.5), "11.0");
  EXPECT_EQ(format_tick(600.0, 200.0), "600");
  EXPECT_EQ(format_tick(0.30000000000000004, 0.1), "0.3");
  EXPECT_EQ(format_tick(-1e-17, 0.1), "0.0");  // never "-0.0"
  EXPECT_EQ(format_tick(-6.0, 1.0), "-6");
  EXPECT_EQ(format_tick(1000.2, 0.2), "1000.2");  // %.4g would print 1000 for every tick
  EXPECT_EQ(format_tick(0.00015, 0.00005), "0.00015");
  EXPECT_EQ(format_tick(1.5e-7, 5e-8), "1.5e-07");
  EXPECT_EQ(format_tick(3e7, 1e7), "3e+07");
  EXPECT_EQ(format_tick(std::numeric_limits<double>::quiet_NaN(), 1.0), "n/a");
}

TEST(SvgPlotAxes, LabelsTicksMarkersBandsAndLegendColumn) {
  const std::vector<double> t = {10.0, 11.0, 12.0, 13.0, 14.0};
  const std::vector<double> y = {150.0, 600.0, 1050.0, 350.0, 800.0};
  SvgPlot plot("position", "time t [s]", "strain S [1e-6]", 980, 300);
  plot.set_legend_column(230);
  plot.add_line("setpoint", t, y, "#111111");
  plot.add_band(12.0, 13.0, "faulted", "#d62728");
  plot.add_marker("fault latched", 12.0, "#8b0000");
  const std::string svg = plot.render();
  EXPECT_NE(svg.find(">time t [s]</text>"), std::string::npos);
  EXPECT_NE(svg.find(">strain S [1e-6]</text>"), std::string::npos);
  EXPECT_NE(svg.find(">13</text>"), std::string::npos);    // x ticks every 1 s
  EXPECT_NE(svg.find(">1000</text>"), std::string::npos);  // y ticks every 200
  EXPECT_NE(svg.find(">setpoint</text>"), std::string::npos);
  EXPECT_NE(svg.find(">faulted</text>"), std::string::npos);
  EXPECT_NE(svg.find(">fault latched</text>"), std::string::npos);
  EXPECT_NE(svg.find("fill=\"#d62728\""), std::string::npos);
  // The frame ends where the legend column starts: 980 - 230.
  EXPECT_NE(svg.find("width=\"682.0\""), std::string::npos);  // 750 - 68
  // The marker: a vertical line at 12 s, half way across the frame (68 + 682 / 2).
  EXPECT_NE(svg.find("x1=\"409.0\" y1=\"30.0\" x2=\"409.0\""), std::string::npos);
  EXPECT_EQ(count(svg, "<svg"), count(svg, "</svg>"));
}

TEST(SvgPlotAxes, IncludeXLinesUpStackedPlots) {
  const std::vector<double> t = {11.0, 12.0};
  const std::vector<double> y = {1.0, 2.0};
  SvgPlot plot("error", "time t [s]", "error [1e-6]", 980, 220);
  plot.include_x(10.0);
  plot.include_x(14.0);
  plot.add_line("e", t, y, "#000");
  const std::string svg = plot.render();
  EXPECT_NE(svg.find(">10</text>"), std::string::npos);
  EXPECT_NE(svg.find(">14</text>"), std::string::npos);
}

}  // namespace
}  // namespace selfsense::report
