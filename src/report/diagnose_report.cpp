#include "selfsense/report/diagnose_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <fstream>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "selfsense/report/svg_plot.hpp"

namespace selfsense::report {
namespace {

constexpr std::string_view kRecordedColour = "#222222";
constexpr std::string_view kBeforeColour = "#d95f02";
constexpr std::string_view kAfterColour = "#1f77b4";
constexpr std::string_view kBoundColour = "#c00000";
constexpr std::string_view kBoundLabel = "\u00B1bound (99 %)";  // UTF-8, as the page says
constexpr std::size_t kMaxSegmentsListed = 12;

constexpr std::string_view kStyle = R"(
body { font-family: "DejaVu Sans", Arial, sans-serif; margin: 16px 24px; color: #222;
       max-width: 1200px; }
h1 { font-size: 22px; margin: 0 0 8px; }
h2 { font-size: 18px; border-bottom: 1px solid #ccc; margin-top: 28px; }
h3 { font-size: 15px; margin: 16px 0 4px; }
table { border-collapse: collapse; margin: 6px 0; }
th, td { border: 1px solid #ccc; padding: 3px 8px; text-align: left; vertical-align: top; }
td.n { text-align: right; font-variant-numeric: tabular-nums; }
code { background: #f3f3f3; padding: 0 3px; word-break: break-all; }
.verdict { padding: 1px 8px; border-radius: 4px; color: #fff; }
.v-mismatch { background: #b03a2e; }
.v-consistent { background: #2e7d32; }
.v-unexplained { background: #b9770e; }
.v-other { background: #666; }
.plots { display: flex; flex-wrap: wrap; gap: 8px 16px; }
figure { margin: 0; }
figcaption { font-size: 12px; color: #555; max-width: 560px; }
p.note { color: #555; }
)";

std::string percent(double fraction) {
  return std::isfinite(fraction) ? format_number(100.0 * fraction) + " %" : "n/a";
}

std::string seconds(double t) {
  return format_number(t) + " s";
}

std::string segment_list(const std::vector<ReportSegment>& where) {
  if (where.empty()) return "whole recording";
  std::string out;
  const std::size_t shown = std::min(where.size(), kMaxSegmentsListed);
  for (std::size_t i = 0; i < shown; ++i) {
    if (i > 0) out += ", ";
    out += format_number(where[i].t_start) + "&ndash;" + seconds(where[i].t_end);
  }
  if (where.size() > shown) out += " and " + std::to_string(where.size() - shown) + " more";
  return out;
}

// The time axis for n samples: t when it covers them, else the sample index.
struct TimeAxis {
  std::span<const double> t;  // empty when t is too short
  std::vector<double> index;  // the sample index then
  std::string label;

  [[nodiscard]] bool in_seconds() const { return !t.empty(); }
  [[nodiscard]] std::span<const double> first(std::size_t n) const {
    return (in_seconds() ? t : std::span<const double>(index)).first(n);
  }
};

TimeAxis time_axis(const ReportInput& input, std::size_t n) {
  TimeAxis axis;
  if (n > 0 && input.t.size() >= n) {
    axis.t = std::span<const double>(input.t).first(n);
    axis.label = "t [s]";
    return axis;
  }
  axis.index.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    axis.index[i] = static_cast<double>(i);
  axis.label = "sample (no time column for all samples)";
  return axis;
}

std::vector<double> difference(const std::vector<double>& a, const std::vector<double>& b) {
  const std::size_t n = std::min(a.size(), b.size());
  std::vector<double> out(n);
  for (std::size_t i = 0; i < n; ++i)
    out[i] = a[i] - b[i];
  return out;
}

std::string with_unit(std::string_view name, std::string_view unit) {
  std::string out(name);
  if (!unit.empty()) out += " [" + std::string(unit) + "]";
  return out;
}

std::string figure(const SvgPlot& plot, const std::string& caption) {
  std::string out = "<figure>\n" + plot.render();
  if (!caption.empty()) out += "<figcaption>" + caption + "</figcaption>\n";
  out += "</figure>\n";
  return out;
}

const ReportFigure* find_figure(const std::vector<ReportFigure>& figures, const std::string& ch) {
  const auto it = std::find_if(figures.begin(), figures.end(),
                               [&](const ReportFigure& f) { return f.channel == ch; });
  return it == figures.end() ? nullptr : &*it;
}

void add_name(std::vector<std::string>& names, const std::vector<ReportFigure>& figures) {
  for (const ReportFigure& f : figures) {
    if (std::find(names.begin(), names.end(), f.channel) == names.end()) {
      names.push_back(f.channel);
    }
  }
}

std::string figure_cell(const ReportFigure* f, bool nrmse) {
  if (f == nullptr) return "<td class=\"n\">&ndash;</td>";
  return "<td class=\"n\">" + percent(nrmse ? f->nrmse : f->max) + "</td>";
}

std::string header_section(const ReportInput& in) {
  std::string verdict_class = "v-other";
  if (in.verdict == "mismatch") verdict_class = "v-mismatch";
  if (in.verdict == "consistent") verdict_class = "v-consistent";
  if (in.verdict == "unexplained") verdict_class = "v-unexplained";
  const std::string verdict = in.verdict.empty() ? "no verdict" : in.verdict;
  std::string out = "<h1>selfsense diagnose: <span class=\"verdict " + verdict_class + "\">" +
                    escape_html(verdict) + "</span></h1>\n<table class=\"paths\">\n";
  out += "<tr><th>model</th><td><code>" + escape_html(in.model_path) + "</code></td></tr>\n";
  out +=
      "<tr><th>recording</th><td><code>" + escape_html(in.recording_path) + "</code></td></tr>\n";
  out += "<tr><th>validation</th><td>" +
         (in.validate_path.empty() ? std::string("none (no --validate)")
                                   : "<code>" + escape_html(in.validate_path) + "</code>") +
         "</td></tr>\n";
  out += "<tr><th>samples</th><td>" + std::to_string(in.t.size()) + "</td></tr>\n</table>\n";
  return out;
}

std::string fit_section(const ReportInput& in) {
  std::string out =
      "<section id=\"fit\">\n<h2>Fit before and after</h2>\n"
      "<p class=\"note\">nrmse: RMS of (recorded &minus; model); max: largest |recorded &minus; "
      "model|; both as % of the recorded channel's range.</p>\n";
  std::vector<std::string> names;
  add_name(names, in.fit_before);
  add_name(names, in.fit_after);
  add_name(names, in.validation_before);
  add_name(names, in.validation_after);
  if (names.empty()) return out + "<p>No fit figures.</p>\n</section>\n";
  const bool validation = !in.validation_before.empty() || !in.validation_after.empty();
  out += "<table>\n<tr><th rowspan=\"2\">channel</th><th colspan=\"4\">recording</th>";
  if (validation) out += "<th colspan=\"4\">validation</th>";
  out += "</tr>\n<tr>";
  const int groups = validation ? 2 : 1;
  for (int g = 0; g < groups; ++g) {
    out += "<th>nrmse before</th><th>nrmse after</th><th>max before</th><th>max after</th>";
  }
  out += "</tr>\n";
  for (const std::string& name : names) {
    out += "<tr><td>" + escape_html(name) + "</td>";
    out += figure_cell(find_figure(in.fit_before, name), true);
    out += figure_cell(find_figure(in.fit_after, name), true);
    out += figure_cell(find_figure(in.fit_before, name), false);
    out += figure_cell(find_figure(in.fit_after, name), false);
    if (validation) {
      out += figure_cell(find_figure(in.validation_before, name), true);
      out += figure_cell(find_figure(in.validation_after, name), true);
      out += figure_cell(find_figure(in.validation_before, name), false);
      out += figure_cell(find_figure(in.validation_after, name), false);
    }
    out += "</tr>\n";
  }
  return out + "</table>\n</section>\n";
}

std::string findings_section(const ReportInput& in) {
  std::string out = "<section id=\"findings\">\n<h2>Findings</h2>\n";
  for (const std::string& u : in.unexplained)
    out += "<p class=\"unexplained\">unexplained: " + escape_html(u) + "</p>\n";
  if (in.findings.empty()) {
    if (!in.unexplained.empty()) return out + "</section>\n";
    return out + "<p>consistent: nothing left that the data can support naming</p>\n</section>\n";
  }
  out +=
      "<table>\n<tr><th>effect</th><th>channel</th><th>explains</th><th>evidence</th>"
      "<th>where</th></tr>\n";
  for (const ReportFinding& f : in.findings) {
    out += "<tr><td>" + escape_html(f.effect) + "</td><td>" + escape_html(f.channel) +
           "</td><td class=\"n\">" + percent(f.explains) + "</td><td>" + escape_html(f.evidence) +
           "</td><td>" + segment_list(f.where) + "</td></tr>\n";
  }
  out += "</table>\n<ul>\n";
  for (const ReportFinding& f : in.findings) {
    out += "<li><b>" + escape_html(f.effect) + "</b> on " + escape_html(f.channel) + " explains " +
           percent(f.explains) + " of the residual variance: " + escape_html(f.evidence);
    if (!f.alternatives.empty()) {
      out += "\n<br>Explaining nearly as much, not told apart by these data:<ul>\n";
      for (const ReportFinding::Alternative& a : f.alternatives) {
        out += "<li><b>" + escape_html(a.effect) + "</b> would explain " + percent(a.explains) +
               ": " + escape_html(a.evidence) + "</li>\n";
      }
      out += "</ul>";
    }
    out += "</li>\n";
  }
  return out + "</ul>\n</section>\n";
}

std::string residual_section(const ReportInput& in) {
  std::string out =
      "<section id=\"residuals\">\n<h2>Residual over time</h2>\n"
      "<p class=\"note\">recorded &minus; model, before and after the added physics; shaded: "
      "the located segments.</p>\n";
  if (in.channels.empty()) return out + "<p>No channels.</p>\n</section>\n";
  for (const ReportChannel& ch : in.channels) {
    out += "<h3>" + escape_html(ch.name) + "</h3>\n";
    const std::vector<double> before = difference(ch.recorded, ch.before);
    const std::vector<double> after = difference(ch.recorded, ch.after);
    if (before.empty() && after.empty()) {
      out += "<p>No data for channel " + escape_html(ch.name) + ".</p>\n";
      continue;
    }
    const TimeAxis axis = time_axis(in, std::max(before.size(), after.size()));
    SvgPlot plot(ch.name + ": residual (recorded - model)", axis.label,
                 with_unit(ch.name + " residual", ch.unit), 900, 300);
    if (axis.in_seconds()) {
      for (const ReportSegment& s : ch.located)
        plot.add_band(s.t_start, s.t_end);
    }
    plot.add_line("before", axis.first(before.size()), before, std::string(kBeforeColour));
    plot.add_line("after", axis.first(after.size()), after, std::string(kAfterColour));
    std::string caption = std::to_string(ch.located.size()) + " located segment" +
                          (ch.located.size() == 1 ? "" : "s");
    if (!ch.located.empty()) caption += ": " + segment_list(ch.located);
    out += "<div class=\"plots\">\n" + figure(plot, caption) + "</div>\n";
  }
  return out + "</section>\n";
}

std::string loop_plot(const ReportInput& in, const ReportChannel& ch,
                      const std::vector<double>& model, std::string_view which,
                      std::string_view colour) {
  const std::size_t nr = std::min(in.drive.size(), ch.recorded.size());
  const std::size_t nm = std::min(in.drive.size(), model.size());
  SvgPlot plot(ch.name + " against " + in.drive_name + ", " + std::string(which),
               with_unit(in.drive_name, in.drive_unit), with_unit(ch.name, ch.unit));
  const std::span<const double> drive(in.drive);
  plot.add_line("recorded", drive.first(nr), std::span<const double>(ch.recorded).first(nr),
                std::string(kRecordedColour));
  plot.add_line("model " + std::string(which), drive.first(nm),
                std::span<const double>(model).first(nm), std::string(colour));
  return figure(plot, "");
}

std::string loops_section(const ReportInput& in) {
  std::string out =
      "<section id=\"loops\">\n<h2>Input-output loops</h2>\n"
      "<p class=\"note\">The drive " +
      escape_html(in.drive_name) +
      " on x; the recorded output and the model before (left) and after (right) on y.</p>\n";
  if (in.channels.empty()) return out + "<p>No channels.</p>\n</section>\n";
  for (const ReportChannel& ch : in.channels) {
    out += "<h3>" + escape_html(ch.name) + "</h3>\n";
    if (in.drive.empty() || (ch.recorded.empty() && ch.before.empty() && ch.after.empty())) {
      out += "<p>No data for channel " + escape_html(ch.name) + ".</p>\n";
      continue;
    }
    out += "<div class=\"plots\">\n" + loop_plot(in, ch, ch.before, "before", kBeforeColour) +
           loop_plot(in, ch, ch.after, "after", kAfterColour) + "</div>\n";
  }
  return out + "</section>\n";
}

std::string features_section(const ReportInput& in) {
  std::string out =
      "<section id=\"features\">\n<h2>Residual against the explaining feature</h2>\n"
      "<p class=\"note\">Per finding: the residual before the added physics against the feature "
      "that explains it.</p>\n";
  if (in.findings.empty()) return out + "<p>No findings.</p>\n</section>\n";
  out += "<div class=\"plots\">\n";
  for (const ReportFinding& f : in.findings) {
    std::string unit;
    for (const ReportChannel& ch : in.channels) {
      if (ch.name == f.channel) unit = ch.unit;
    }
    const std::string feature = f.feature_name.empty() ? "feature" : f.feature_name;
    SvgPlot plot(f.effect + " (" + f.channel + ")", feature,
                 with_unit(f.channel + " residual before", unit));
    plot.add_scatter("residual", f.feature, f.residual, std::string(kBeforeColour));
    out += figure(plot, escape_html(f.effect) + ": explains " + percent(f.explains));
  }
  return out + "</div>\n</section>\n";
}

std::size_t outside(const std::vector<double>& values, double bound, std::size_t skip) {
  std::size_t n = 0;
  for (std::size_t i = skip; i < values.size(); ++i) {
    if (std::abs(values[i]) > bound) ++n;
  }
  return n;
}

std::string correlation_plot(const ReportCorrelation& c, bool cross, std::string_view which,
                             std::string_view colour, const std::string& channel,
                             const std::string& drive) {
  const std::vector<double>& values = cross ? c.cross_correlation : c.autocorrelation;
  const auto half = static_cast<double>(values.empty() ? 0 : (values.size() - 1) / 2);
  std::vector<double> lags(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    lags[i] = static_cast<double>(i) - (cross ? half : 0.0);
  }
  const std::string title =
      cross ? channel + " residual \xC3\x97 " + drive + ", " + std::string(which)
            : channel + " residual autocorrelation, " + std::string(which);
  SvgPlot plot(title, "lag [samples]", cross ? "cross-correlation" : "autocorrelation");
  plot.add_stems(std::string(which), lags, values, std::string(colour));
  const double bound = std::abs(c.bound);
  if (bound > 0.0) {
    plot.add_reference(std::string(kBoundLabel), bound, std::string(kBoundColour));
    plot.add_reference(std::string(kBoundLabel), -bound, std::string(kBoundColour));
  }
  std::string caption;
  if (!values.empty()) {
    // Lag 0 of the autocorrelation is 1 by definition and not a test.
    const std::size_t skip = cross ? 0 : 1;
    caption = std::to_string(outside(values, bound, skip)) + " of " +
              std::to_string(values.size() - std::min(skip, values.size())) +
              " lags outside &plusmn;" + format_number(bound);
  }
  return figure(plot, caption);
}

std::string tests_section(const ReportInput& in) {
  std::string out =
      "<section id=\"tests\">\n<h2>Correlation tests</h2>\n"
      "<p class=\"note\">A white residual stays inside the dashed &plusmn;bound (99 % confidence) "
      "at every lag: autocorrelation at lags 0..max_lag, cross-correlation with the drive at "
      "lags &minus;max_lag..max_lag.</p>\n";
  if (in.channels.empty()) return out + "<p>No channels.</p>\n</section>\n";
  for (const ReportChannel& ch : in.channels) {
    out += "<h3>" + escape_html(ch.name) + "</h3>\n<div class=\"plots\">\n";
    out += correlation_plot(ch.test_before, false, "before", kBeforeColour, ch.name, in.drive_name);
    out += correlation_plot(ch.test_after, false, "after", kAfterColour, ch.name, in.drive_name);
    out += correlation_plot(ch.test_before, true, "before", kBeforeColour, ch.name, in.drive_name);
    out += correlation_plot(ch.test_after, true, "after", kAfterColour, ch.name, in.drive_name);
    out += "</div>\n";
  }
  return out + "</section>\n";
}

}  // namespace

void write_diagnosis_report(const ReportInput& input, const std::filesystem::path& path) {
  std::string html =
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; "
      "style-src 'unsafe-inline'\">\n<title>selfsense diagnose: " +
      escape_html(input.verdict) + "</title>\n<style>" + std::string(kStyle) +
      std::string(plot_style()) + "</style>\n</head>\n<body>\n";
  html += header_section(input);
  html += fit_section(input);
  html += findings_section(input);
  html += residual_section(input);
  html += loops_section(input);
  html += features_section(input);
  html += tests_section(input);
  html += "</body>\n</html>\n";

  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  if (!file) throw std::runtime_error("cannot write the report " + path.string());
  file.write(html.data(), static_cast<std::streamsize>(html.size()));
  file.close();
  if (!file) throw std::runtime_error("cannot write the report " + path.string());
}

}  // namespace selfsense::report
