// A small inline-SVG plot writer for the HTML reports (`selfsense diagnose`, the main job's page):
// line, scatter and stem series on linear axes with ticks at 1, 2 or 5 times a power of ten,
// axis labels with their units, a legend, shaded x bands, vertical markers and horizontal
// reference lines. Long series are reduced while they are added, so a plot stays a few ten
// kilobytes for 1e6 samples.
#pragma once

#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace selfsense::report {

// Text for HTML (element content and attribute values): & < > " ' as entities.
[[nodiscard]] std::string escape_html(std::string_view text);

// %.4g; "n/a" for NaN or infinity, so no "nan" or "inf" reaches a report.
[[nodiscard]] std::string format_number(double value);

// The CSS the plots' classes expect (axis text, title, grid, markers), for a page's <style>.
[[nodiscard]] std::string_view plot_style();

// Tick positions for an axis over lo..hi: every multiple of the step inside the range, the step
// 1, 2 or 5 times a power of ten and the smallest such step giving at most about `target`
// intervals. Empty for an empty, reversed or non-finite range; never more than a dozen.
[[nodiscard]] std::vector<double> nice_ticks(double lo, double hi, int target = 5);
// The step nice_ticks() uses: the smallest 1, 2 or 5 x 10^k at least span / target; 0 when
// span or target is not positive and finite.
[[nodiscard]] double nice_step(double span, int target = 5);
// A tick's label: as many decimals as the step needs (0.1 0.2 0.3, 1000.5 1001 -> "1000.5"
// "1001.0"), never "-0"; %g with enough digits to tell ticks apart where fixed notation would be
// long (steps below 1e-6, values of 1e7 and more); "n/a" for a non-finite value.
[[nodiscard]] std::string format_tick(double value, double step);

class SvgPlot {
 public:
  static constexpr int kDefaultWidth = 560;
  static constexpr int kDefaultHeight = 300;

  SvgPlot(std::string title, std::string x_label, std::string y_label, int width = kDefaultWidth,
          int height = kDefaultHeight);

  // y against x joined in order. Reduced to the samples with the smallest and largest y per
  // pixel column when x increases (a time series), otherwise to the steps of the pen between
  // cells of a grid coarse enough for the point budget, each step drawn once (a loop).
  void add_line(std::string label, std::span<const double> x, std::span<const double> y,
                std::string colour);
  // Points; reduced to one point per occupied cell of a grid coarse enough for the budget.
  void add_scatter(std::string label, std::span<const double> x, std::span<const double> y,
                   std::string colour);
  // Vertical stems from 0 to y at each x.
  void add_stems(std::string label, std::span<const double> x, std::span<const double> y,
                 std::string colour);
  // A dashed horizontal line across the plot (e.g. a confidence bound); in the legend once.
  void add_reference(std::string label, double y, std::string colour);
  // A shaded band over x0..x1 across the full height (e.g. a located segment); with a label,
  // in the legend once per label.
  void add_band(double x0, double x1);
  void add_band(double x0, double x1, std::string label, std::string colour);
  // A dashed vertical line at x across the plot (e.g. where a fault latched), in the legend.
  void add_marker(std::string label, double x, std::string colour);
  // Forces the y (x) range to include these values (e.g. 0 and the bounds of a test; the
  // time span of a plot stacked under another, so their axes line up).
  void include_y(double y);
  void include_x(double x);
  // Puts the legend in a column this wide right of the frame instead of inside it, top right:
  // nothing is hidden under it, and stacked plots of one width and column line up.
  void set_legend_column(int width);

  // The <svg> element; a plot without any finite data says so in its frame.
  [[nodiscard]] std::string render() const;

  // Points of all series after reduction (the size the SVG will have).
  [[nodiscard]] std::size_t point_count() const;

 private:
  enum class Kind { kLine, kScatter, kStems };
  struct Series {
    std::string label;
    Kind kind{Kind::kLine};
    std::string colour;
    std::vector<double> x;  // reduced data, NaN separates line pieces
    std::vector<double> y;
    // The range of the data before the reduction (the axes cover all of it).
    double x_lo{0.0};
    double x_hi{0.0};
    double y_lo{0.0};
    double y_hi{0.0};
  };
  struct Reference {
    std::string label;
    double y{0.0};
    std::string colour;
  };
  struct Band {
    double x0{0.0};
    double x1{0.0};
    std::string label{};
    std::string colour{};
  };
  struct Marker {
    std::string label;
    double x{0.0};
    std::string colour;
  };

  void add_series(std::string label, Kind kind, std::span<const double> x,
                  std::span<const double> y, std::string colour);

  std::string title_;
  std::string x_label_;
  std::string y_label_;
  int width_;
  int height_;
  std::vector<Series> series_;
  std::vector<Reference> references_;
  std::vector<Band> bands_;
  std::vector<Marker> markers_;
  std::vector<double> extra_y_;
  std::vector<double> extra_x_;
  int legend_column_{0};
};

}  // namespace selfsense::report
