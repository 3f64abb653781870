// The HTML report of `selfsense diagnose`: sections, escaping, well-formed SVG, no NaN text,
// bounded size for long recordings, and the plot reduction behind it.
#include "selfsense/report/diagnose_report.hpp"

#include <gtest/gtest.h>

#include <cctype>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "cli/report_sample.hpp"
#include "selfsense/report/svg_plot.hpp"

namespace selfsense::report {
namespace {

namespace fs = std::filesystem;

class DiagnoseReport : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("selfsense_report_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const ReportInput& in) {
    const fs::path path = dir_ / "report.html";
    write_diagnosis_report(in, path);
    std::ifstream file(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
  }

  fs::path dir_;
};

std::size_t count(std::string_view text, std::string_view what) {
  std::size_t n = 0;
  for (std::size_t pos = text.find(what); pos != std::string_view::npos;
       pos = text.find(what, pos + what.size())) {
    ++n;
  }
  return n;
}

// Whole words "nan", "inf" or "infinity" in any case (numbers printed from non-finite values).
bool has_non_finite_text(std::string_view text) {
  std::string lower(text);
  for (char& c : lower)
    c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  const auto alpha = [&](std::size_t i) {
    return i < lower.size() && std::isalpha(static_cast<unsigned char>(lower[i])) != 0;
  };
  for (const std::string_view word : {"nan", "inf", "infinity"}) {
    for (std::size_t pos = lower.find(word); pos != std::string::npos;
         pos = lower.find(word, pos + 1)) {
      if ((pos == 0 || !alpha(pos - 1)) && !alpha(pos + word.size())) return true;
    }
  }
  return false;
}

// Every <svg> is closed after it opens and before the next opens.
bool svgs_balanced(std::string_view html) {
  std::size_t pos = 0;
  while ((pos = html.find("<svg", pos)) != std::string_view::npos) {
    const std::size_t close = html.find("</svg>", pos);
    const std::size_t next = html.find("<svg", pos + 4);
    if (close == std::string_view::npos || (next != std::string_view::npos && next < close)) {
      return false;
    }
    pos = close;
  }
  return count(html, "<svg") == count(html, "</svg>");
}

TEST_F(DiagnoseReport, HasEverySectionAndPlot) {
  const std::string html = write(test::make_sample_report(100000));
  for (const char* section :
       {"id=\"fit\"", "id=\"findings\"", "id=\"residuals\"", "id=\"loops\"", "id=\"features\"",
        "id=\"tests\"", "Fit before and after", "Findings", "Residual over time",
        "Input-output loops", "Residual against the explaining feature", "Correlation tests"}) {
    EXPECT_NE(html.find(section), std::string::npos) << section;
  }
  EXPECT_NE(html.find("mismatch"), std::string::npos);
  EXPECT_NE(html.find("creep"), std::string::npos);
  EXPECT_NE(html.find("charge_leakage"), std::string::npos);
  EXPECT_NE(html.find("log10 time since last step [s]"), std::string::npos);
  EXPECT_NE(html.find("data/validation.csv"), std::string::npos);
  EXPECT_NE(html.find("83 %"), std::string::npos);  // explains, as a percentage
  // An alternative is shown with its own figure and evidence, escaped.
  EXPECT_NE(html.find("<b>hysteresis</b> would explain 70 %: the recorded S differs on rising "
                      "&amp; falling branches &lt;here&gt;"),
            std::string::npos);
  EXPECT_NE(html.find("12 %"), std::string::npos);  // S nrmse before
  // Per channel: one residual plot, two loops, four correlation plots; one scatter per finding.
  EXPECT_EQ(count(html, "<svg"), 2U * 7U + 2U);
  EXPECT_TRUE(svgs_balanced(html));
  EXPECT_EQ(html.rfind("</html>"), html.size() - 8);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  // No resource from elsewhere: the only address is the SVG namespace.
  EXPECT_EQ(count(html, "http:"), count(html, "http://www.w3.org/2000/svg"));
  EXPECT_EQ(count(html, "https:"), 0U);
  EXPECT_EQ(count(html, "src="), 0U);
}

TEST_F(DiagnoseReport, EscapesText) {
  const std::string html = write(test::make_sample_report(1000));
  EXPECT_EQ(html.find("<script>"), std::string::npos);
  EXPECT_NE(html.find("models/&lt;script&gt;alert(1)&lt;/script&gt;.yaml"), std::string::npos);
  EXPECT_NE(html.find("data/run &quot;A&quot; &amp; &#39;B&#39;.csv"), std::string::npos);
  EXPECT_NE(html.find("0.91 &gt; 0.5 &amp; p &lt; 1e-6"), std::string::npos);
  EXPECT_NE(html.find("C/m^2"), std::string::npos);
}

TEST_F(DiagnoseReport, NoNonFiniteNumbers) {
  ReportInput in = test::make_sample_report(10000);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  in.channels[0].recorded[100] = nan;
  in.channels[1].before[200] = inf;
  in.findings[0].feature[5] = -inf;
  in.fit_after[0].nrmse = nan;
  in.channels[0].test_after.autocorrelation[3] = nan;
  in.channels[1].located.push_back({nan, 3.0});
  const std::string html = write(in);
  EXPECT_FALSE(has_non_finite_text(html));
  EXPECT_NE(html.find("n/a"), std::string::npos);
  EXPECT_TRUE(svgs_balanced(html));
  // The checker itself finds such text.
  EXPECT_TRUE(has_non_finite_text("<text>nan</text>"));
  EXPECT_TRUE(has_non_finite_text("x=\"-inf\""));
  EXPECT_FALSE(has_non_finite_text("information, finance"));
}

TEST_F(DiagnoseReport, MillionSamplesStaySmall) {
  const std::string html = write(test::make_sample_report(1000000));
  EXPECT_LT(html.size(), 2U * 1024U * 1024U) << html.size() << " bytes";
  EXPECT_TRUE(svgs_balanced(html));
  EXPECT_FALSE(has_non_finite_text(html));
}

TEST_F(DiagnoseReport, EmptyInputSaysConsistent) {
  ReportInput in;
  in.verdict = "consistent";
  const std::string html = write(in);
  EXPECT_NE(html.find("consistent: nothing left that the data can support naming"),
            std::string::npos);
  EXPECT_NE(html.find("none (no --validate)"), std::string::npos);
  EXPECT_EQ(count(html, "<svg"), 0U);
  EXPECT_FALSE(has_non_finite_text(html));
}

TEST_F(DiagnoseReport, ChannelWithoutDataAndNoFindings) {
  ReportInput in = test::make_sample_report(2000);
  in.verdict = "consistent";
  in.findings.clear();
  ReportChannel empty;
  empty.name = "T_hat";
  empty.unit = "Pa";
  in.channels.push_back(empty);
  const std::string html = write(in);
  EXPECT_NE(html.find("No data for channel T_hat"), std::string::npos);
  EXPECT_NE(html.find("consistent: nothing left that the data can support naming"),
            std::string::npos);
  // Two channels with data (7 plots each); the empty one has its 4 (empty) test plots.
  EXPECT_EQ(count(html, "<svg"), 2U * 7U + 4U);
  EXPECT_NE(html.find("no data"), std::string::npos);
  EXPECT_TRUE(svgs_balanced(html));
  EXPECT_FALSE(has_non_finite_text(html));
}

TEST_F(DiagnoseReport, WithoutTimeDrawsAgainstTheSampleIndex) {
  ReportInput in = test::make_sample_report(1000);
  in.t.clear();
  const std::string html = write(in);
  EXPECT_NE(html.find("sample (no time column for all samples)"), std::string::npos);
  EXPECT_EQ(html.find("#f5c242"), std::string::npos);          // segments in s cannot be shaded
  EXPECT_NE(html.find("0.1&ndash;0.2 s"), std::string::npos);  // still listed
  EXPECT_TRUE(svgs_balanced(html));
}

TEST_F(DiagnoseReport, UnwritablePathThrowsNamingIt) {
  const fs::path path = dir_ / "missing" / "report.html";
  try {
    write_diagnosis_report(test::make_sample_report(10), path);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
  }
}

TEST(SvgPlot, TimeSeriesKeepsMinAndMaxPerColumn) {
  const std::size_t n = 1000000;
  std::vector<double> t(n);
  std::vector<double> y(n, 0.0);
  for (std::size_t i = 0; i < n; ++i)
    t[i] = static_cast<double>(i) * 1e-3;
  y[500001] = 7.0;  // one sample; must survive the reduction
  SvgPlot plot("spike", "t [s]", "y", 900, 300);
  plot.add_line("y", t, y, "#000");
  EXPECT_LE(plot.point_count(), 2U * 900U);
  const std::string svg = plot.render();
  EXPECT_NE(svg.find(">6</text>"), std::string::npos);  // the y axis reaches the spike
  // y 7 of -0.35..7.35 (5 % room) in the frame 30..254 px: the line goes up to 40.2 px.
  const std::size_t path = svg.find("<path d=\"");
  ASSERT_NE(path, std::string::npos);
  EXPECT_NE(svg.find(" 40.2", path), std::string::npos);
}

TEST(SvgPlot, LoopsAndScattersHaveABudget) {
  const std::size_t n = 1000000;
  std::vector<double> x(n);
  std::vector<double> y(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double phase = 2.0 * 3.141592653589793 * 40.0 * static_cast<double>(i) / 1e6;
    const double amplitude = 1.0 - 0.9 * static_cast<double>(i) / 1e6;
    x[i] = amplitude * std::sin(phase);
    y[i] = amplitude * std::sin(phase - 0.5) + 1e-3 * std::sin(7919.0 * static_cast<double>(i));
  }
  SvgPlot loop("loop", "x", "y");
  loop.add_line("loop", x, y, "#000");
  EXPECT_LE(loop.point_count(), 3000U);
  EXPECT_GE(loop.point_count(), 500U);
  SvgPlot scatter("scatter", "x", "y");
  scatter.add_scatter("points", x, y, "#000");
  EXPECT_LE(scatter.point_count(), 3000U);
  EXPECT_GE(scatter.point_count(), 500U);
}

TEST(SvgPlot, ExtremeRangesNeitherHangNorPrintNaN) {
  const std::vector<double> offset_x = {1.7e18, 1.7e18 + 1024.0, 1.7e18 + 4096.0};
  const std::vector<double> huge_y = {-1.0e308, 0.0, 1.0e308};
  SvgPlot plot("extreme", "x", "y");
  plot.add_line("a", offset_x, huge_y, "#000");
  plot.add_scatter("b", huge_y, huge_y, "#000");
  const std::string svg = plot.render();
  EXPECT_FALSE(has_non_finite_text(svg));
  EXPECT_EQ(count(svg, "<svg"), count(svg, "</svg>"));
}

TEST(SvgPlot, EmptyPlotSaysNoData) {
  SvgPlot plot("empty", "x", "y");
  plot.add_line("nothing", {}, {}, "#000");
  const std::string svg = plot.render();
  EXPECT_NE(svg.find("no data"), std::string::npos);
  EXPECT_EQ(count(svg, "<svg"), count(svg, "</svg>"));
}

TEST(HtmlText, EscapesAndFormats) {
  EXPECT_EQ(escape_html("<a href=\"x\">'&'</a>"),
            "&lt;a href=&quot;x&quot;&gt;&#39;&amp;&#39;&lt;/a&gt;");
  EXPECT_EQ(format_number(0.000123456), "0.0001235");
  EXPECT_EQ(format_number(1234567.0), "1.235e+06");
  EXPECT_EQ(format_number(std::numeric_limits<double>::quiet_NaN()), "n/a");
  EXPECT_EQ(format_number(-std::numeric_limits<double>::infinity()), "n/a");
}

}  // namespace
}  // namespace selfsense::report
