#include "selfsense/report/main_job_page.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <fstream>
#include <stdexcept>
#include <string_view>

#include "selfsense/report/svg_plot.hpp"

namespace selfsense::report {
namespace {

constexpr double kNoValue = std::numeric_limits<double>::quiet_NaN();
constexpr int kWidth = 980;
constexpr int kLegendColumn = 230;
constexpr int kMainHeight = 300;
constexpr int kErrorHeight = 220;
constexpr int kFieldHeight = 180;
constexpr int kTemperatureHeight = 220;
constexpr double kPerMicro = 1e6;        // strain [-] -> [1e-6]
constexpr double kMegaPerUnit = 1e-6;    // Pa -> MPa, V/m -> kV/mm (1 kV/mm = 1e6 V/m)
constexpr double kRestFraction = 0.6;    // the rest: the mean from 60 % of the samples on
constexpr double kBeforePeak = 0.05;     // [s] of the ring-down window before the peak
constexpr double kRingDownWindow = 0.4;  // [s]
constexpr double kModePosition = 0.0;    // the recording's `mode` code
constexpr std::string_view kTimeLabel = "time t [s]";
constexpr std::string_view kSetpointColour = "#111111";
constexpr std::string_view kEstimateColour = "#1f77b4";
constexpr std::string_view kReferenceColour = "#d62728";
constexpr std::string_view kFieldColour = "#2ca02c";
constexpr std::string_view kTemperatureColour = "#d62728";
constexpr std::string_view kEquivalentColour = "#1f77b4";
constexpr std::string_view kFaultedColour = "#d62728";
constexpr std::string_view kReadyColour = "#999999";
constexpr std::string_view kMarkerColour = "#8b0000";
constexpr std::string_view kZeroColour = "#888888";

constexpr std::string_view kPageStyle = R"(
body { font-family: "DejaVu Sans", Arial, sans-serif; margin: 16px 24px; color: #222;
       max-width: 1200px; }
h1 { font-size: 22px; margin: 0 0 8px; }
h2 { font-size: 18px; border-bottom: 1px solid #ccc; margin-top: 28px; }
p.fig { font-family: "DejaVu Sans Mono", monospace; font-size: 13px; }
p.note, figcaption { font-size: 12px; color: #555; }
figure { margin: 0 0 8px; }
li.fault { color: #8b0000; }
)";

// The quantities of a run's plots: their names, axis labels and the factor from SI.
struct Quantity {
  std::string symbol;  // "S" or "T"
  std::string axis;    // "strain S [1e-6]"
  std::string error_axis;
  double scale{1.0};
};

Quantity quantity_of(MainJobRun::Kind kind) {
  if (kind == MainJobRun::Kind::kForce) {
    return Quantity{"T", "stress T [MPa]", "error [MPa]", kMegaPerUnit};
  }
  return Quantity{"S", "strain S [1e-6]", "error [1e-6]", kPerMicro};
}

std::vector<double> scaled(std::span<const double> v, double factor) {
  std::vector<double> out(v.size());
  std::transform(v.begin(), v.end(), out.begin(), [factor](double x) { return factor * x; });
  return out;
}

// Spans outside the armed state shaded (faulted red, ready grey) and the fault's moment marked.
void mark_states(SvgPlot& plot, const MainJobRun& run) {
  const std::size_t n = std::min(run.t.size(), run.state.size());
  std::size_t i = 0;
  while (i < n) {
    if (run.state[i] == kStateArmed) {
      ++i;
      continue;
    }
    const double code = run.state[i];
    const std::size_t first = i;
    while (i < n && run.state[i] == code)
      ++i;
    // To the next sample's time, so one sample is a visible sliver.
    const double end = i < n ? run.t[i] : run.t[i - 1];
    if (code == kStateFaulted) {
      plot.add_band(run.t[first], end, "faulted", std::string(kFaultedColour));
    } else {
      plot.add_band(run.t[first], end, "not armed", std::string(kReadyColour));
    }
  }
  if (std::isfinite(run.fault_t)) {
    plot.add_marker("fault latched", run.fault_t, std::string(kMarkerColour));
  }
}

std::string page_figure(const SvgPlot& plot, const std::string& caption) {
  std::string out = "<figure>\n" + plot.render();
  if (!caption.empty()) out += "<figcaption>" + caption + "</figcaption>\n";
  return out + "</figure>\n";
}

std::string fault_caption(const MainJobRun& run) {
  if (!std::isfinite(run.fault_t)) return "";
  return " Dashed dark red: the fault latched at t = " + format_number(run.fault_t) + " s (" +
         escape_html(run.fault_text) + "); shaded red: samples in the faulted state.";
}

// The self-heating run: the self-sensing error over the whole run, and the plant's temperature
// against the adaptation's equivalent temperature. Nothing without a recorded temperature.
std::string temperature_plots(const MainJobRun& run, std::span<const double> t) {
  const std::size_t n = t.size();
  const bool has_temperature = run.temperature.size() >= n;
  const bool has_equivalent = run.temperature_estimate.size() >= n;
  if (n == 0 || (!has_temperature && !has_equivalent)) return "";
  const Quantity q = quantity_of(run.kind);
  std::string out;
  if (run.reference.size() >= n && run.estimate.size() >= n) {
    std::vector<double> error(n);
    for (std::size_t i = 0; i < n; ++i)
      error[i] = q.scale * (run.estimate[i] - run.reference[i]);
    SvgPlot err(run.heading + ": self-sensing error", std::string(kTimeLabel),
                q.symbol + "_hat - " + q.symbol + " " + q.error_axis.substr(6), kWidth,
                kErrorHeight);
    err.set_legend_column(kLegendColumn);
    mark_states(err, run);
    err.add_reference("", 0.0, std::string(kZeroColour));
    err.add_line(q.symbol + "_hat - " + q.symbol, t, error, std::string(kEstimateColour));
    out += page_figure(err,
                       "The estimate against the plant's truth over every sample, the fast sine "
                       "that warms the stack included.");
  }
  SvgPlot temp(run.heading + ": the stack's temperature", std::string(kTimeLabel),
               "temperature [degC]", kWidth, kTemperatureHeight);
  temp.set_legend_column(kLegendColumn);
  mark_states(temp, run);
  if (has_temperature) {
    temp.add_line("plant (true)", t, std::span<const double>(run.temperature).first(n),
                  std::string(kTemperatureColour));
  }
  if (has_equivalent) {
    temp.add_line("equivalent (adaptation)", t,
                  std::span<const double>(run.temperature_estimate).first(n),
                  std::string(kEquivalentColour));
  }
  out += page_figure(
      temp, std::string("Red: the simulated stack's temperature (the plant's self-heating, "
                        "never seen by the loop)") +
                (has_equivalent ? "; blue: the equivalent temperature the adaptation "
                                  "learns from E and D alone."
                                : "; this run does not adapt."));
  return out;
}

std::string tracking_plots(const MainJobRun& run) {
  const Quantity q = quantity_of(run.kind);
  const std::size_t n = std::min({run.t.size(), run.setpoint.size(), run.estimate.size()});
  const std::span<const double> t = std::span<const double>(run.t).first(n);
  const std::span<const double> setpoint = std::span<const double>(run.setpoint).first(n);
  const std::span<const double> estimate = std::span<const double>(run.estimate).first(n);
  const bool has_reference = run.reference.size() >= n;
  const std::string hat = q.symbol + "_hat";

  SvgPlot main(run.heading + ": setpoint, " + hat + " and true " + q.symbol,
               std::string(kTimeLabel), q.axis, kWidth, kMainHeight);
  main.set_legend_column(kLegendColumn);
  mark_states(main, run);
  main.add_line("setpoint", t, scaled(setpoint, q.scale), std::string(kSetpointColour));
  main.add_line(hat + " (self-sensed)", t, scaled(estimate, q.scale), std::string(kEstimateColour));
  if (has_reference) {
    main.add_line(q.symbol + " (plant, true)", t,
                  scaled(std::span<const double>(run.reference).first(n), q.scale),
                  std::string(kReferenceColour));
  }
  std::string out = page_figure(
      main, "Black: the setpoint; blue: " + hat +
                ", the loop's self-sensed estimate from E and D only; red: " + q.symbol +
                ", the simulated plant's truth, never seen by the loop." + fault_caption(run));

  std::vector<bool> settled = settled_samples(t, setpoint, run.state);
  if (run.kind == MainJobRun::Kind::kPosition && run.mode.size() >= n) {
    for (std::size_t i = 0; i < n; ++i)
      settled[i] = settled[i] && run.mode[i] == kModePosition;
  }
  std::vector<double> error_hat(n, kNoValue);
  std::vector<double> error_true(n, kNoValue);
  for (std::size_t i = 0; i < n; ++i) {
    if (!settled[i]) continue;
    error_hat[i] = q.scale * (estimate[i] - setpoint[i]);
    if (has_reference) error_true[i] = q.scale * (run.reference[i] - setpoint[i]);
  }
  SvgPlot error(run.heading + ": tracking error", std::string(kTimeLabel), q.error_axis, kWidth,
                kErrorHeight);
  error.set_legend_column(kLegendColumn);
  if (n > 0) {
    error.include_x(t.front());
    error.include_x(t.back());
  }
  mark_states(error, run);
  error.add_reference("", 0.0, std::string(kZeroColour));
  error.add_line(hat + " - setpoint", t, error_hat, std::string(kEstimateColour));
  if (has_reference) {
    error.add_line(q.symbol + " - setpoint", t, error_true, std::string(kReferenceColour));
  }
  out +=
      page_figure(error, "The error the figures measure: over the armed samples from " +
                             format_number(kSettleTime) + " s after each setpoint step on" +
                             (run.kind == MainJobRun::Kind::kPosition ? ", in position mode" : "") +
                             " (the gaps are the samples not counted).");

  out += temperature_plots(run, t);
  if (run.field.size() >= n) {
    SvgPlot field(run.heading + ": the field the loop drives", std::string(kTimeLabel),
                  "field E [kV/mm]", kWidth, kFieldHeight);
    field.set_legend_column(kLegendColumn);
    mark_states(field, run);
    field.add_line("E", t, scaled(std::span<const double>(run.field).first(n), kMegaPerUnit),
                   std::string(kFieldColour));
    out += page_figure(field, "");
  }
  return out;
}

std::string ring_down_plots(const MainJobRun& run) {
  const std::size_t n = std::min(run.t.size(), run.estimate.size());
  const bool has_reference = run.reference.size() >= n;
  const RingDownWindow w = ring_down_window(run);
  std::vector<double> t;
  std::vector<double> reference;
  std::vector<double> estimate;
  std::vector<double> error;
  for (std::size_t i = 0; i < n; ++i) {
    if (w.valid && (run.t[i] < w.t0 || run.t[i] > w.t1)) continue;
    t.push_back(run.t[i]);
    estimate.push_back(kPerMicro * (run.estimate[i] - w.rest_estimate));
    if (has_reference) {
      reference.push_back(kPerMicro * (run.reference[i] - w.rest_reference));
      error.push_back(kPerMicro * (run.estimate[i] - run.reference[i]));
    }
  }
  SvgPlot main(run.heading + ": S minus its rest after the impulse", std::string(kTimeLabel),
               "strain S - rest [1e-6]", kWidth, kMainHeight);
  main.set_legend_column(kLegendColumn);
  mark_states(main, run);
  main.add_reference("", 0.0, std::string(kZeroColour));
  if (has_reference) main.add_line("S (plant, true)", t, reference, std::string(kReferenceColour));
  main.add_line("S_hat (self-sensed)", t, estimate, std::string(kEstimateColour));
  std::string caption =
      w.valid ? "A 300 N impulse of 0.5 ms from the bench; " + format_number(kRingDownWindow) +
                    " s from " + format_number(kBeforePeak) +
                    " s before the largest deviation; the rest: the mean of the last 40 % of "
                    "the armed samples. Red: true S; blue: S_hat, the signal the loop damps."
              : "No armed sample: the whole recording, S and S_hat as recorded.";
  std::string out = page_figure(main, caption + fault_caption(run));
  if (has_reference) {
    SvgPlot err(run.heading + ": self-sensing error", std::string(kTimeLabel), "S_hat - S [1e-6]",
                kWidth, kErrorHeight);
    err.set_legend_column(kLegendColumn);
    if (!t.empty()) {
      err.include_x(t.front());
      err.include_x(t.back());
    }
    mark_states(err, run);
    err.add_reference("", 0.0, std::string(kZeroColour));
    err.add_line("S_hat - S", t, error, std::string(kEstimateColour));
    out += page_figure(err, "The estimate's error against the plant's truth in the same window.");
  }
  return out;
}

std::string run_section(const MainJobRun& run) {
  std::string out = "<section>\n<h2>" + escape_html(run.heading) + "</h2>\n";
  if (!run.figures.empty()) out += "<p class=\"fig\">" + escape_html(run.figures) + "</p>\n";
  if (!run.recording.empty()) {
    out += "<p class=\"note\">recording: <code>" + escape_html(run.recording) + "</code></p>\n";
  }
  if (!run.error.empty()) return out + "<p>" + escape_html(run.error) + "</p>\n</section>\n";
  out += run.kind == MainJobRun::Kind::kRingDown ? ring_down_plots(run) : tracking_plots(run);
  return out + "</section>\n";
}

}  // namespace

std::vector<bool> settled_samples(std::span<const double> t, std::span<const double> setpoint,
                                  std::span<const double> state) {
  const std::size_t n = std::min({t.size(), setpoint.size(), state.size()});
  std::vector<bool> settled(t.size(), false);
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i) {
    if (state[i] != kStateArmed) continue;
    lo = std::min(lo, setpoint[i]);
    hi = std::max(hi, setpoint[i]);
  }
  if (!(lo <= hi)) return settled;
  const double step = kSetpointStepFraction * (hi - lo);
  bool first = true;
  double last_jump = 0.0;
  double previous = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    if (state[i] != kStateArmed) continue;
    if (first) {
      first = false;
      last_jump = t[i];
    } else {
      if (std::abs(setpoint[i] - previous) > step) last_jump = t[i];
      settled[i] = t[i] - last_jump >= kSettleTime;
    }
    previous = setpoint[i];
  }
  return settled;
}

RingDownWindow ring_down_window(const MainJobRun& run) {
  const std::size_t n = std::min(run.t.size(), run.estimate.size());
  const bool has_reference = run.reference.size() >= n;
  std::vector<std::size_t> armed;
  for (std::size_t i = 0; i < n; ++i) {
    if (i < run.state.size() && run.state[i] == kStateArmed) armed.push_back(i);
  }
  RingDownWindow w;
  if (armed.empty()) return w;
  const auto from = static_cast<std::size_t>(kRestFraction * static_cast<double>(armed.size()));
  const auto rest = [&](const std::vector<double>& v) {
    double sum = 0.0;
    std::size_t count = 0;
    for (std::size_t k = from > 0 ? from - 1 : 0; k < armed.size(); ++k, ++count)
      sum += v[armed[k]];
    return sum / static_cast<double>(count);
  };
  w.rest_estimate = rest(run.estimate);
  w.rest_reference = has_reference ? rest(run.reference) : w.rest_estimate;
  const std::vector<double>& v = has_reference ? run.reference : run.estimate;
  std::size_t at = armed.front();
  double peak = -1.0;
  for (const std::size_t i : armed) {
    const double d = std::abs(v[i] - w.rest_reference);
    if (d > peak) {
      peak = d;
      at = i;
    }
  }
  w.valid = true;
  w.t0 = run.t[at] - kBeforePeak;
  w.t1 = w.t0 + kRingDownWindow;
  return w;
}

std::string main_job_page_html(const MainJobPage& page) {
  std::string html =
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; "
      "style-src 'unsafe-inline'\">\n<title>selfsense main job</title>\n<style>" +
      std::string(kPageStyle) + std::string(plot_style()) + "</style>\n</head>\n<body>\n<h1>" +
      escape_html(page.title) + "</h1>\n";
  if (!page.fault_lines.empty()) {
    html += "<h2>faulted runs, done again</h2>\n<ul>\n";
    for (const std::string& line : page.fault_lines)
      html += "<li class=\"fault\">" + escape_html(line) + "</li>\n";
    html += "</ul>\n";
  }
  for (const MainJobRun& run : page.runs)
    html += run_section(run);
  for (const std::string& line : page.summary)
    html += "<p><b>" + escape_html(line) + "</b></p>\n";
  for (const MainJobRun& run : page.faulted_runs)
    html += run_section(run);
  return html + "</body>\n</html>\n";
}

void write_main_job_page(const MainJobPage& page, const std::filesystem::path& path) {
  const std::string html = main_job_page_html(page);
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  if (!file) throw std::runtime_error("cannot write the page " + path.string());
  file.write(html.data(), static_cast<std::streamsize>(html.size()));
  file.close();
  if (!file) throw std::runtime_error("cannot write the page " + path.string());
}

}  // namespace selfsense::report
