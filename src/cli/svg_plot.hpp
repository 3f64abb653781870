// A small inline-SVG plot writer for the HTML reports: line, scatter and stem series on linear
// axes with ticks, labels, a legend, shaded x bands and horizontal reference lines. Long series
// are reduced while they are added, so a plot stays a few ten kilobytes for 1e6 samples.
#pragma once

#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace selfsense::cli {

// Text for HTML (element content and attribute values): & < > " ' as entities.
[[nodiscard]] std::string escape_html(std::string_view text);

// %.4g; "n/a" for NaN or infinity, so no "nan" or "inf" reaches a report.
[[nodiscard]] std::string format_number(double value);

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
  // A shaded band over x0..x1 across the full height (e.g. a located segment).
  void add_band(double x0, double x1);
  // Forces the y range to include these values (e.g. 0 and the bounds of a test).
  void include_y(double y);

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
  std::vector<double> extra_y_;
};

}  // namespace selfsense::cli
