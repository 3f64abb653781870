// `selfsense diagnose` (docs/diagnose.md): locate where a model and a recording differ, name the
// physics the model leaves out, model it, write the improved model, the JSON result and the
// HTML report, with the fit before and after on the recording and on --validate data.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

// After the standard headers, which define __GLIBC__.
#ifdef __GLIBC__
#include <malloc.h>
#endif

#include "commands.hpp"
#include "field_signals.hpp"
#include "model_runs.hpp"
#include "selfsense/diagnosis/diagnosis.hpp"
#include "selfsense/io/recording.hpp"
#include "selfsense/model_io/model_yaml.hpp"
#include "selfsense/report/diagnose_report.hpp"

namespace selfsense::cli {

using report::ReportChannel;
using report::ReportCorrelation;
using report::ReportFigure;
using report::ReportFinding;
using report::ReportInput;
using report::ReportSegment;
using report::write_diagnosis_report;
namespace {

struct DiagnoseOptions {
  std::filesystem::path model{};
  std::filesystem::path recording{};
  std::filesystem::path validate{};
  std::filesystem::path json{};
  std::filesystem::path report{};
  std::filesystem::path out{};
  double min_explains{0.3};
};

FieldSignals load_signals(const std::filesystem::path& path, const models::TransducerModel& m) {
  const io::Recording rec = io::read_recording_csv(path, io::ReadOptions{{"t"}});
  return field_signals(rec, path.string(), m.geometry, m.drive());
}

diagnosis::Signals to_signals(const FieldSignals& f, models::Drive drive) {
  return {f.drive(drive), f.sensed(drive), f.s, f.stress, f.temp, f.sample_time};
}

// Forward and reconstruction through the runtime model (with the recorded temperature).
std::vector<ChannelFigures> figures_of(const models::TransducerModel& model,
                                       const FieldSignals& f) {
  return figures(model, f, run_model(model, f, true, true), 0, f.size());
}

std::vector<ReportFigure> report_figures(const std::vector<ChannelFigures>& figs) {
  std::vector<ReportFigure> out;
  out.reserve(figs.size());
  for (const ChannelFigures& c : figs)
    out.push_back({c.channel, c.figures.nrmse, c.figures.max});
  return out;
}

std::vector<ReportSegment> seconds(const std::vector<diagnosis::Segment>& segs,
                                   const std::vector<double>& t) {
  std::vector<ReportSegment> out;
  out.reserve(segs.size());
  for (const diagnosis::Segment& s : segs) {
    out.push_back({t[s.begin], t[std::min(s.end, t.size()) - 1]});
  }
  return out;
}

ReportCorrelation correlation(const std::string& channel, const diagnosis::CorrelationTest& c) {
  return {channel, c.max_lag, c.autocorrelation, c.cross_correlation, c.bound};
}

void write_json(const std::filesystem::path& path, const nlohmann::json& j) {
  std::ofstream file(path);
  if (!file || !(file << j.dump(2) << '\n') || !file.flush()) {
    throw std::runtime_error(path.string() + ": cannot write the diagnosis");
  }
}

void run(const DiagnoseOptions& opt) {
  const auto started = std::chrono::steady_clock::now();
  // The diagnosis allocates and frees columns of a whole recording (8 MB at 1e6 samples) for
  // every candidate it fits; glibc would map each from the kernel afresh and fault every page
  // in again (a third of the time on the 1e6-sample bench). Kept in the heap, they are reused.
#ifdef __GLIBC__
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
#endif
  const models::TransducerModel model = models::load_model(opt.model);
  const FieldSignals rec = load_signals(opt.recording, model);
  if (rec.sensed(model.drive()).empty() && rec.s.empty()) {
    throw io::RecordingError(rec.source + ": no reference channel to diagnose the model against " +
                             "(needs S or x, or the sensed channel " +
                             (model.drive() == models::Drive::kField ? "D or q)" : "E or u)"));
  }
  diagnosis::Options options;
  options.min_explains = opt.min_explains;
  const diagnosis::Result result =
      diagnosis::diagnose(model, to_signals(rec, model.drive()), options);

  nlohmann::json j;
  j["verdict"] = diagnosis::to_string(result.verdict);
  j["findings"] = nlohmann::json::array();
  for (const diagnosis::Finding& f : result.findings) {
    nlohmann::json where = nlohmann::json::array();
    for (const ReportSegment& s : seconds(f.where, rec.t)) {
      where.push_back({{"t_start", s.t_start}, {"t_end", s.t_end}});
    }
    nlohmann::json alternatives = nlohmann::json::array();
    for (const diagnosis::Alternative& a : f.alternatives) {
      alternatives.push_back(
          {{"effect", a.effect}, {"explains", a.explains}, {"evidence", a.evidence}});
    }
    j["findings"].push_back({{"effect", f.effect},
                             {"channel", f.channel},
                             {"where", where},
                             {"explains", f.explains},
                             {"evidence", f.evidence},
                             {"alternatives", alternatives}});
  }
  j["unexplained"] = nlohmann::json::array();
  for (const diagnosis::Unexplained& u : result.unexplained) {
    nlohmann::json where = nlohmann::json::array();
    for (const ReportSegment& s : seconds(u.where, rec.t)) {
      where.push_back({{"t_start", s.t_start}, {"t_end", s.t_end}});
    }
    j["unexplained"].push_back({{"channel", u.channel},
                                {"where", where},
                                {"share", u.share},
                                {"residual_rms", u.residual_rms},
                                {"noise_floor", u.noise_floor}});
  }
  const std::vector<ChannelFigures> before = figures_of(model, rec);
  const std::vector<ChannelFigures> after = figures_of(result.improved, rec);
  j["fit"] = {{"before", to_json(before)}, {"after", to_json(after)}};
  ReportInput report;
  std::vector<ChannelFigures> vb;
  std::vector<ChannelFigures> va;
  if (!opt.validate.empty()) {
    const FieldSignals val = load_signals(opt.validate, model);
    vb = figures_of(model, val);
    va = figures_of(result.improved, val);
    j["validation"] = {{"before", to_json(vb)}, {"after", to_json(va)}};
    report.validation_before = report_figures(vb);
    report.validation_after = report_figures(va);
  }
  nlohmann::json channels = nlohmann::json::array();
  for (const diagnosis::ChannelResult& c : result.channels) {
    nlohmann::json located = nlohmann::json::array();
    for (const ReportSegment& s : seconds(c.located, rec.t)) {
      located.push_back({{"t_start", s.t_start}, {"t_end", s.t_end}});
    }
    const auto test = [](const diagnosis::CorrelationTest& t) {
      return nlohmann::json{{"bound", t.bound},
                            {"autocorrelation_outside", t.auto_outside},
                            {"cross_correlation_outside", t.cross_outside}};
    };
    channels.push_back(
        {{"channel", c.channel},
         {"noise_floor", c.noise_floor},
         {"residual_rms", c.residual_rms},
         {"located", located},
         {"residual_test", {{"before", test(c.test_before)}, {"after", test(c.test_after)}}}});
  }
  j["channels"] = channels;
  write_json(opt.json, j);

  std::string notes = "diagnosed_from: " + opt.model.filename().string() + "\nfindings: [";
  for (std::size_t i = 0; i < result.findings.size(); ++i) {
    notes += (i ? ", " : "") + result.findings[i].effect + " " + result.findings[i].channel;
  }
  notes += "]\n";
  models::save_model(result.improved, opt.out, notes);

  report.model_path = opt.model.string();
  report.recording_path = opt.recording.string();
  report.validate_path = opt.validate.string();
  report.verdict = j["verdict"];
  for (const diagnosis::Unexplained& u : result.unexplained) {
    const std::vector<ReportSegment> where = seconds(u.where, rec.t);
    char line[256];
    static_cast<void>(std::snprintf(
        line, sizeof line,
        "%s: residual RMS %.3g, %.1fx its noise floor %.3g; %.0f %% of it in %zu "
        "stretch(es) between %.3g s and %.3g s; no candidate reduces it on held-out data",
        u.channel.c_str(), u.residual_rms,
        u.noise_floor > 0.0 ? u.residual_rms / u.noise_floor : 0.0, u.noise_floor, 100.0 * u.share,
        where.size(), where.empty() ? 0.0 : where.front().t_start,
        where.empty() ? 0.0 : where.back().t_end));
    report.unexplained.emplace_back(line);
  }
  report.t = rec.t;
  const std::span<const double> drive = rec.drive(model.drive());
  report.drive.assign(drive.begin(), drive.end());
  if (model.drive() == models::Drive::kCharge) {
    report.drive_name = "D";
    report.drive_unit = "C/m^2";
  }
  for (const diagnosis::ChannelResult& c : result.channels) {
    ReportChannel rc;
    rc.name = c.channel;
    rc.unit = c.channel == "S" ? "-" : (c.channel == "D" ? "C/m^2" : "V/m");
    rc.recorded = c.recorded;
    rc.before = c.before;
    rc.after = c.after;
    rc.located = seconds(c.located, rec.t);
    rc.test_before = correlation(c.channel, c.test_before);
    rc.test_after = correlation(c.channel, c.test_after);
    report.channels.push_back(std::move(rc));
  }
  for (const diagnosis::Finding& f : result.findings) {
    ReportFinding rf;
    rf.effect = f.effect;
    rf.channel = f.channel;
    rf.where = seconds(f.where, rec.t);
    rf.explains = f.explains;
    rf.evidence = f.evidence;
    for (const diagnosis::Alternative& a : f.alternatives)
      rf.alternatives.push_back({a.effect, a.explains, a.evidence});
    rf.feature_name = f.feature_name;
    rf.feature = f.feature;
    for (const diagnosis::ChannelResult& c : result.channels) {
      if (c.channel != f.channel) continue;
      rf.residual.resize(c.recorded.size());
      for (std::size_t k = 0; k < c.recorded.size(); ++k)
        rf.residual[k] = c.recorded[k] - c.before[k];
    }
    report.findings.push_back(std::move(rf));
  }
  report.fit_before = report_figures(before);
  report.fit_after = report_figures(after);
  write_diagnosis_report(report, opt.report);

  std::printf("verdict: %s\n", diagnosis::to_string(result.verdict));
  for (const diagnosis::Finding& f : result.findings) {
    std::printf("  %s on %s (explains %.0f %%): %s\n", f.effect.c_str(), f.channel.c_str(),
                100.0 * f.explains, f.evidence.c_str());
  }
  for (const std::string& u : report.unexplained)
    std::printf("  unexplained on %s\n", u.c_str());
  const auto print = [](const char* what, const std::vector<ChannelFigures>& b,
                        const std::vector<ChannelFigures>& a) {
    for (std::size_t i = 0; i < b.size() && i < a.size(); ++i) {
      std::printf("  %-10s %-6s nrmse %.4g %% -> %.4g %%\n", what, b[i].channel.c_str(),
                  100.0 * b[i].figures.nrmse, 100.0 * a[i].figures.nrmse);
    }
  };
  print("fit", before, after);
  print("validation", vb, va);
  const double seconds_taken =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  std::printf("wrote %s, %s, %s (%.1f s)\n", opt.json.string().c_str(), opt.report.string().c_str(),
              opt.out.string().c_str(), seconds_taken);
}

}  // namespace

void add_diagnose_command(CLI::App& app) {
  auto opt = std::make_shared<DiagnoseOptions>();
  CLI::App* cmd = app.add_subcommand(
      "diagnose", "Locate where model and recording differ, name and model the missing physics");
  cmd->add_option("--model", opt->model, "Model (YAML)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--recording", opt->recording, "Recording with references (CSV)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--validate", opt->validate, "Recording used for figures only (CSV)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--json", opt->json, "Result (JSON)")->required();
  cmd->add_option("--report", opt->report, "Report (HTML)")->required();
  cmd->add_option("--out", opt->out, "Improved model (YAML)")->required();
  cmd->add_option("--min-explains", opt->min_explains,
                  "Share of held-out residual variance an effect must remove to be named")
      ->check(CLI::Range(0.0, 1.0));
  cmd->callback([opt] { run(*opt); });
}

}  // namespace selfsense::cli
