#include "selfsense/report/svg_plot.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string_view>
#include <system_error>
#include <unordered_set>
#include <utility>

namespace selfsense::report {
namespace {

constexpr int kMarginLeft = 68;
constexpr int kMarginRight = 14;
constexpr int kMarginTop = 30;
constexpr int kMarginBottom = 46;
constexpr std::size_t kLoopBudget = 3000;
constexpr std::size_t kScatterBudget = 3000;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::size_t kMaxTicks = 12;
constexpr double kBandOpacity = 0.3;
constexpr std::string_view kDefaultBandColour = "#f5c242";

constexpr std::string_view kPlotStyle = R"(
svg.plot { max-width: 100%; height: auto; }
svg.plot text { font-size: 11px; fill: #222; }
svg.plot .pt { font-size: 13px; font-weight: bold; }
svg.plot .al { font-size: 12px; }
svg.plot .gr { stroke: #e6e6e6; }
)";

struct Range {
  double lo{std::numeric_limits<double>::infinity()};
  double hi{-std::numeric_limits<double>::infinity()};

  void include(double v) {
    if (!std::isfinite(v)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  [[nodiscard]] bool empty() const { return !(lo <= hi); }
  [[nodiscard]] double span() const { return hi - lo; }
};

Range range_of(std::span<const double> v) {
  Range r;
  for (const double x : v)
    r.include(x);
  return r;
}

// A range with room: never zero wide, padded by a fraction of its width.
Range widened(Range r, double pad) {
  if (r.empty()) return Range{0.0, 1.0};
  if (r.span() <= 0.0) {
    const double half = r.lo == 0.0 ? 1.0 : 0.1 * std::abs(r.lo);
    return Range{r.lo - half, r.hi + half};
  }
  const double p = pad * r.span();
  return Range{r.lo - p, r.hi + p};
}

// Pixel cell of v within r split into n cells (0..n-1).
std::size_t cell_of(double v, const Range& r, std::size_t n) {
  if (r.span() <= 0.0) return 0;
  const double f = (v - r.lo) / r.span() * static_cast<double>(n);
  const auto c = static_cast<std::size_t>(std::max(0.0, f));
  return std::min(c, n - 1);
}

bool increasing(std::span<const double> x, std::span<const double> y) {
  double last = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (!std::isfinite(x[i]) || !std::isfinite(y[i])) continue;
    if (x[i] < last) return false;
    last = x[i];
  }
  return true;
}

struct Reduced {
  std::vector<double> x;
  std::vector<double> y;

  void push(double xv, double yv) {
    x.push_back(xv);
    y.push_back(yv);
  }
  void gap() {
    if (!x.empty() && !std::isnan(x.back())) push(kNaN, kNaN);
  }
};

// Time series: per pixel column the samples with the smallest and largest y, in sample order.
Reduced reduce_columns(std::span<const double> x, std::span<const double> y, std::size_t columns) {
  Reduced out;
  const Range rx = range_of(x);
  if (rx.empty()) return out;
  std::size_t column = std::numeric_limits<std::size_t>::max();
  std::size_t lo = 0;
  std::size_t hi = 0;
  bool open = false;
  const auto flush = [&] {
    if (!open) return;
    const std::size_t first = std::min(lo, hi);
    const std::size_t second = std::max(lo, hi);
    out.push(x[first], y[first]);
    if (second != first) out.push(x[second], y[second]);
    open = false;
  };
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (!std::isfinite(x[i]) || !std::isfinite(y[i])) {
      flush();
      out.gap();
      column = std::numeric_limits<std::size_t>::max();
      continue;
    }
    const std::size_t c = cell_of(x[i], rx, columns);
    if (!open || c != column) {
      flush();
      column = c;
      lo = hi = i;
      open = true;
      continue;
    }
    if (y[i] < y[lo]) lo = i;
    if (y[i] > y[hi]) hi = i;
  }
  flush();
  return out;
}

// A path in x and y (a loop traced many times): each step of the pen from one cell of a grid
// of cell x cell pixels to another is drawn once; steps already drawn are skipped (the pen
// lifts). The grid coarsens until the budget holds, so no segment is longer than a few cells
// unless the data jump.
Reduced reduce_path(std::span<const double> x, std::span<const double> y, std::size_t columns,
                    std::size_t rows) {
  const Range rx = range_of(x);
  const Range ry = range_of(y);
  constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();
  for (std::size_t cell = 1;; cell *= 2) {
    const std::size_t nx = std::max<std::size_t>(1, columns / cell);
    const std::size_t ny = std::max<std::size_t>(1, rows / cell);
    const bool last_try = nx == 1 && ny == 1;
    Reduced out;
    std::unordered_set<std::uint64_t> drawn;
    std::size_t last = kNone;
    std::size_t last_index = 0;     // the sample where the pen entered the cell `last`
    std::size_t pen_index = kNone;  // the sample the output ends on
    for (std::size_t i = 0; i < x.size(); ++i) {
      if (!std::isfinite(x[i]) || !std::isfinite(y[i])) {
        last = kNone;
        continue;
      }
      const std::size_t c = cell_of(x[i], rx, nx) * ny + cell_of(y[i], ry, ny);
      if (c == last) continue;
      if (last != kNone) {
        const std::size_t lo = std::min(c, last);
        const std::size_t hi = std::max(c, last);
        if (drawn.insert((static_cast<std::uint64_t>(lo) << 32U) | hi).second) {
          if (pen_index != last_index) {
            out.gap();
            out.push(x[last_index], y[last_index]);
          }
          out.push(x[i], y[i]);
          pen_index = i;
        }
      } else {
        out.gap();
        out.push(x[i], y[i]);  // a dot where a piece starts
        pen_index = i;
      }
      last = c;
      last_index = i;
      if (out.x.size() > kLoopBudget && !last_try) break;
    }
    if (out.x.size() <= kLoopBudget || last_try) return out;
  }
}

// Points: the first point in each occupied cell; the grid coarsens until the budget holds.
Reduced reduce_points(std::span<const double> x, std::span<const double> y, std::size_t columns,
                      std::size_t rows) {
  const Range rx = range_of(x);
  const Range ry = range_of(y);
  for (std::size_t cell = 1;; cell *= 2) {
    const std::size_t nx = std::max<std::size_t>(1, columns / cell);
    const std::size_t ny = std::max<std::size_t>(1, rows / cell);
    std::vector<bool> taken(nx * ny, false);
    Reduced out;
    for (std::size_t i = 0; i < x.size(); ++i) {
      if (!std::isfinite(x[i]) || !std::isfinite(y[i])) continue;
      const std::size_t c = cell_of(x[i], rx, nx) * ny + cell_of(y[i], ry, ny);
      if (taken[c]) continue;
      taken[c] = true;
      out.push(x[i], y[i]);
    }
    if (out.x.size() <= kScatterBudget || (nx == 1 && ny == 1)) return out;
  }
}

// A pixel coordinate: one decimal, no exponent.
void append_coordinate(std::string& out, double v) {
  // Ranges near the limits of double can make a coordinate overflow; never print nan or inf.
  v = std::isfinite(v) ? std::clamp(v, -1.0e6, 1.0e6) : 0.0;
  std::array<char, 32> buf{};
  const auto [end, ec] =
      std::to_chars(buf.data(), buf.data() + buf.size(), v, std::chars_format::fixed, 1);
  if (ec != std::errc{}) {
    out += '0';
    return;
  }
  out.append(buf.data(), end);
}

// out += every part, without temporaries.
template <typename... Parts>
void append(std::string& out, const Parts&... parts) {
  (out.append(parts), ...);
}

std::string coordinate(double v) {
  std::string s;
  append_coordinate(s, v);
  return s;
}

}  // namespace

std::string_view plot_style() {
  return kPlotStyle;
}

double nice_step(double span, int target) {
  if (!(span > 0.0) || !std::isfinite(span) || target <= 0) return 0.0;
  const double raw = span / static_cast<double>(target);
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double m : {1.0, 2.0, 5.0}) {
    // (1 + 1e-9): a span of exactly 5 steps keeps the step, rounding aside.
    if (m * power * (1.0 + 1e-9) >= raw) return m * power;
  }
  return 10.0 * power;
}

std::vector<double> nice_ticks(double lo, double hi, int target) {
  std::vector<double> out;
  const double step = nice_step(hi - lo, target);
  if (!(step > 0.0) || !std::isfinite(step)) return out;
  const double first = std::ceil(lo / step - 1e-9);
  // k + 1 == k far from zero (a range small against its offset) ends it too.
  for (double k = first; k * step <= hi + 1e-9 * step && out.size() < kMaxTicks; k += 1.0) {
    const double v = k * step;
    if (!out.empty() && v <= out.back()) break;
    out.push_back(std::abs(v) < 1e-9 * step ? 0.0 : v);
  }
  return out;
}

std::string format_tick(double value, double step) {
  if (!std::isfinite(value)) return "n/a";
  if (!(step > 0.0) || !std::isfinite(step)) return format_number(value);
  std::array<char, 48> buf{};
  const double decimals = std::max(0.0, -std::floor(std::log10(step) + 1e-9));
  int n = 0;
  if (decimals <= 6.0 && std::abs(value) < 1e7) {
    if (std::abs(value) < 0.5 * step) value = 0.0;  // no "-0.0"
    n = std::snprintf(buf.data(), buf.size(), "%.*f", static_cast<int>(decimals), value);
  } else {
    // Digits from the value's leading one down to the step's.
    const double lead = value == 0.0 ? 0.0 : std::floor(std::log10(std::abs(value)));
    const int digits =
        static_cast<int>(std::clamp(lead - std::floor(std::log10(step)) + 1.0, 1.0, 15.0));
    n = std::snprintf(buf.data(), buf.size(), "%.*g", digits, value);
  }
  return std::string(buf.data(), static_cast<std::size_t>(std::clamp(n, 0, 47)));
}

std::string escape_html(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string format_number(double value) {
  if (!std::isfinite(value)) return "n/a";
  std::array<char, 32> buf{};
  const int n = std::snprintf(buf.data(), buf.size(), "%.4g", value);
  return std::string(buf.data(), static_cast<std::size_t>(std::max(n, 0)));
}

SvgPlot::SvgPlot(std::string title, std::string x_label, std::string y_label, int width, int height)
    : title_(std::move(title)),
      x_label_(std::move(x_label)),
      y_label_(std::move(y_label)),
      width_(std::max(width, kMarginLeft + kMarginRight + 40)),
      height_(std::max(height, kMarginTop + kMarginBottom + 40)) {}

void SvgPlot::add_line(std::string label, std::span<const double> x, std::span<const double> y,
                       std::string colour) {
  add_series(std::move(label), Kind::kLine, x, y, std::move(colour));
}

void SvgPlot::add_scatter(std::string label, std::span<const double> x, std::span<const double> y,
                          std::string colour) {
  add_series(std::move(label), Kind::kScatter, x, y, std::move(colour));
}

void SvgPlot::add_stems(std::string label, std::span<const double> x, std::span<const double> y,
                        std::string colour) {
  add_series(std::move(label), Kind::kStems, x, y, std::move(colour));
  include_y(0.0);
}

void SvgPlot::add_reference(std::string label, double y, std::string colour) {
  if (!std::isfinite(y)) return;
  references_.push_back(Reference{std::move(label), y, std::move(colour)});
}

void SvgPlot::add_band(double x0, double x1) {
  add_band(x0, x1, "", std::string(kDefaultBandColour));
}

void SvgPlot::add_band(double x0, double x1, std::string label, std::string colour) {
  if (!std::isfinite(x0) || !std::isfinite(x1)) return;
  bands_.push_back(Band{std::min(x0, x1), std::max(x0, x1), std::move(label), std::move(colour)});
}

void SvgPlot::add_marker(std::string label, double x, std::string colour) {
  if (!std::isfinite(x)) return;
  markers_.push_back(Marker{std::move(label), x, std::move(colour)});
}

void SvgPlot::include_y(double y) {
  if (std::isfinite(y)) extra_y_.push_back(y);
}

void SvgPlot::include_x(double x) {
  if (std::isfinite(x)) extra_x_.push_back(x);
}

void SvgPlot::set_legend_column(int width) {
  legend_column_ = std::clamp(width, 0, width_ / 2);
}

void SvgPlot::add_series(std::string label, Kind kind, std::span<const double> x,
                         std::span<const double> y, std::string colour) {
  const std::size_t n = std::min(x.size(), y.size());
  x = x.first(n);
  y = y.first(n);
  const auto columns = static_cast<std::size_t>(width_ - kMarginLeft - kMarginRight);
  const auto rows = static_cast<std::size_t>(height_ - kMarginTop - kMarginBottom);
  Reduced reduced;
  switch (kind) {
    case Kind::kLine:
      reduced = increasing(x, y) ? reduce_columns(x, y, columns) : reduce_path(x, y, columns, rows);
      break;
    case Kind::kScatter:
      reduced = reduce_points(x, y, columns, rows);
      break;
    case Kind::kStems:
      for (std::size_t i = 0; i < n; ++i) {
        if (std::isfinite(x[i]) && std::isfinite(y[i])) reduced.push(x[i], y[i]);
      }
      break;
  }
  // Only points finite in both coordinates are drawn, so only they set the axes.
  Range rx;
  Range ry;
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(x[i]) || !std::isfinite(y[i])) continue;
    rx.include(x[i]);
    ry.include(y[i]);
  }
  series_.push_back(Series{std::move(label), kind, std::move(colour), std::move(reduced.x),
                           std::move(reduced.y), rx.lo, rx.hi, ry.lo, ry.hi});
}

std::size_t SvgPlot::point_count() const {
  std::size_t n = 0;
  for (const Series& s : series_)
    n += s.x.size();
  return n;
}

std::string SvgPlot::render() const {
  Range rx;
  Range ry;
  for (const Series& s : series_) {
    rx.include(s.x_lo);
    rx.include(s.x_hi);
    ry.include(s.y_lo);
    ry.include(s.y_hi);
  }
  const bool has_data = !rx.empty();
  for (const double v : extra_x_)
    rx.include(v);
  for (const Reference& r : references_)
    ry.include(r.y);
  for (const double v : extra_y_)
    ry.include(v);
  // Stems at the ends of the range would sit on the frame: a little room for them.
  const bool stems = std::any_of(series_.begin(), series_.end(),
                                 [](const Series& s) { return s.kind == Kind::kStems; });
  const Range xr = widened(rx, stems ? 0.02 : 0.0);
  const Range yr = widened(ry, 0.05);

  const double left = kMarginLeft;
  const double right = width_ - (legend_column_ > 0 ? legend_column_ : kMarginRight);
  const double top = kMarginTop;
  const double bottom = height_ - kMarginBottom;
  const auto px = [&](double v) { return left + (v - xr.lo) / xr.span() * (right - left); };
  const auto py = [&](double v) { return bottom - (v - yr.lo) / yr.span() * (bottom - top); };

  std::string out;
  out.reserve(4096 + 16 * point_count());
  const std::string w = std::to_string(width_);
  const std::string h = std::to_string(height_);
  out += "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"plot\" width=\"" + w + "\" height=\"" +
         h + "\" viewBox=\"0 0 " + w + " " + h + "\" role=\"img\"><title>" + escape_html(title_) +
         "</title>\n";
  out += "<text x=\"" + coordinate((left + right) / 2) +
         "\" y=\"18\" text-anchor=\"middle\" class=\"pt\">" + escape_html(title_) + "</text>\n";
  out += "<rect x=\"" + coordinate(left) + "\" y=\"" + coordinate(top) + "\" width=\"" +
         coordinate(right - left) + "\" height=\"" + coordinate(bottom - top) +
         "\" fill=\"#fff\" stroke=\"#888\"/>\n";
  if (!has_data) {
    out += "<text x=\"" + coordinate((left + right) / 2) + "\" y=\"" +
           coordinate((top + bottom) / 2) +
           "\" text-anchor=\"middle\" fill=\"#888\">no data</text>\n</svg>\n";
    return out;
  }

  for (const Band& b : bands_) {
    const double x0 = std::clamp(px(b.x0), left, right);
    const double x1 = std::clamp(px(b.x1), left, right);
    if (x1 <= x0 && b.x1 > b.x0) continue;  // outside the plot
    append(out, "<rect x=\"", coordinate(x0), "\" y=\"", coordinate(top), "\" width=\"",
           coordinate(std::max(x1 - x0, 1.0)), "\" height=\"", coordinate(bottom - top),
           "\" fill=\"", escape_html(b.colour), "\" fill-opacity=\"", coordinate(kBandOpacity),
           "\"/>\n");
  }

  // Grid and ticks.
  out += "<g class=\"ax\">\n";
  const double x_step = nice_step(xr.span());
  for (const double v : nice_ticks(xr.lo, xr.hi)) {
    const std::string x = coordinate(px(v));
    append(out, "<line x1=\"", x, "\" y1=\"", coordinate(top), "\" x2=\"", x, "\" y2=\"",
           coordinate(bottom + 4), "\" class=\"gr\"/><text x=\"", x, "\" y=\"",
           coordinate(bottom + 16), "\" text-anchor=\"middle\">", format_tick(v, x_step),
           "</text>\n");
  }
  const double y_step = nice_step(yr.span());
  for (const double v : nice_ticks(yr.lo, yr.hi)) {
    const std::string y = coordinate(py(v));
    append(out, "<line x1=\"", coordinate(left - 4), "\" y1=\"", y, "\" x2=\"", coordinate(right),
           "\" y2=\"", y, "\" class=\"gr\"/><text x=\"", coordinate(left - 6), "\" y=\"", y,
           "\" dy=\"0.35em\" text-anchor=\"end\">", format_tick(v, y_step), "</text>\n");
  }
  out += "<text x=\"" + coordinate((left + right) / 2) + "\" y=\"" + coordinate(height_ - 8.0) +
         "\" text-anchor=\"middle\" class=\"al\">" + escape_html(x_label_) + "</text>\n";
  const std::string ylx = coordinate(14);
  const std::string yly = coordinate((top + bottom) / 2);
  out += "<text x=\"" + ylx + "\" y=\"" + yly +
         "\" text-anchor=\"middle\" class=\"al\" transform=\"rotate(-90 " + ylx + " " + yly +
         ")\">" + escape_html(y_label_) + "</text>\n</g>\n";

  for (const Reference& r : references_) {
    const std::string y = coordinate(py(r.y));
    append(out, "<line x1=\"", coordinate(left), "\" y1=\"", y, "\" x2=\"", coordinate(right),
           "\" y2=\"", y, "\" stroke=\"", escape_html(r.colour), "\" stroke-dasharray=\"6 4\"/>\n");
  }

  for (const Series& s : series_) {
    const std::string colour = escape_html(s.colour);
    std::string d;
    d.reserve(14 * s.x.size());
    bool pen_down = false;
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (std::isnan(s.x[i])) {
        pen_down = false;
        continue;
      }
      const double x = px(s.x[i]);
      const double y = py(s.y[i]);
      switch (s.kind) {
        case Kind::kLine:
          d += pen_down ? 'L' : 'M';
          append_coordinate(d, x);
          d += ' ';
          append_coordinate(d, y);
          pen_down = true;
          break;
        case Kind::kScatter:  // a zero-length segment with round caps is a dot
          d += 'M';
          append_coordinate(d, x);
          d += ' ';
          append_coordinate(d, y);
          d += "h0";
          break;
        case Kind::kStems:
          d += 'M';
          append_coordinate(d, x);
          d += ' ';
          append_coordinate(d, py(0.0));
          d += 'V';
          append_coordinate(d, y);
          break;
      }
    }
    switch (s.kind) {
      case Kind::kLine:
        append(out, "<path d=\"", d, "\" fill=\"none\" stroke=\"", colour,
               "\" stroke-width=\"1.2\" stroke-linejoin=\"round\"/>\n");
        break;
      case Kind::kScatter:
        append(out, "<path d=\"", d, "\" fill=\"none\" stroke=\"", colour,
               "\" stroke-width=\"3\" stroke-linecap=\"round\" stroke-opacity=\"0.6\"/>\n");
        break;
      case Kind::kStems:
        append(out, "<path d=\"", d, "\" fill=\"none\" stroke=\"", colour,
               "\" stroke-width=\"2\"/>\n");
        break;
    }
  }

  for (const Marker& m : markers_) {
    const double x = px(m.x);
    if (x < left - 0.5 || x > right + 0.5) continue;
    const std::string xs = coordinate(x);
    append(out, "<line x1=\"", xs, "\" y1=\"", coordinate(top), "\" x2=\"", xs, "\" y2=\"",
           coordinate(bottom), "\" stroke=\"", escape_html(m.colour),
           "\" stroke-width=\"1.5\" stroke-dasharray=\"4 3\"/>\n");
  }

  // Legend: top right inside the frame, or in the column right of it.
  enum class Swatch { kLine, kDashed, kFill };
  struct Entry {
    std::string label;
    std::string colour;
    Swatch swatch{Swatch::kLine};
  };
  std::vector<Entry> entries;
  const auto add_entry = [&entries](const std::string& label, const std::string& colour,
                                    Swatch swatch) {
    if (label.empty()) return;
    const bool seen = std::any_of(entries.begin(), entries.end(),
                                  [&](const Entry& e) { return e.label == label; });
    if (!seen) entries.push_back(Entry{label, colour, swatch});
  };
  for (const Series& s : series_)
    add_entry(s.label, s.colour, Swatch::kLine);
  for (const Reference& r : references_)
    add_entry(r.label, r.colour, Swatch::kDashed);
  for (const Marker& m : markers_)
    add_entry(m.label, m.colour, Swatch::kDashed);
  for (const Band& b : bands_)
    add_entry(b.label, b.colour, Swatch::kFill);
  if (!entries.empty()) {
    std::size_t longest = 0;
    for (const Entry& e : entries)
      longest = std::max(longest, e.label.size());
    const bool column = legend_column_ > 0;
    const double box_w = column ? legend_column_ - 12.0 : 34.0 + 6.5 * static_cast<double>(longest);
    const double box_h = 6.0 + 15.0 * static_cast<double>(entries.size());
    const double x0 = column ? right + 6.0 : right - box_w - 6.0;
    const double y0 = column ? top : top + 6.0;
    out += "<g class=\"lg\"><rect x=\"" + coordinate(x0) + "\" y=\"" + coordinate(y0) +
           "\" width=\"" + coordinate(box_w) + "\" height=\"" + coordinate(box_h) +
           "\" fill=\"#fff\" fill-opacity=\"0.85\" stroke=\"#ccc\"/>\n";
    for (std::size_t i = 0; i < entries.size(); ++i) {
      const double y = y0 + 12.0 + 15.0 * static_cast<double>(i);
      const Entry& e = entries[i];
      const std::string colour = escape_html(e.colour);
      if (e.swatch == Swatch::kFill) {
        append(out, "<rect x=\"", coordinate(x0 + 6), "\" y=\"", coordinate(y - 9),
               "\" width=\"20\"", " height=\"10\" fill=\"", colour, "\" fill-opacity=\"",
               coordinate(kBandOpacity), "\"/>");
      } else {
        append(out, "<line x1=\"", coordinate(x0 + 6), "\" y1=\"", coordinate(y - 4), "\" x2=\"",
               coordinate(x0 + 26), "\" y2=\"", coordinate(y - 4), "\" stroke=\"", colour,
               "\" stroke-width=\"2\"",
               e.swatch == Swatch::kDashed ? " stroke-dasharray=\"6 4\"" : "", "/>");
      }
      append(out, "<text x=\"", coordinate(x0 + 30), "\" y=\"", coordinate(y), "\">",
             escape_html(e.label), "</text>\n");
    }
    out += "</g>\n";
  }
  out += "</svg>\n";
  return out;
}

}  // namespace selfsense::report
