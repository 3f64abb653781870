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
#include "selfsense/diagnosis/diagnosis.hpp"
#include "selfsense/evaluation/diagnosis_output.hpp"
#include "selfsense/evaluation/field_signals.hpp"
#include "selfsense/evaluation/model_runs.hpp"
#include "selfsense/io/recording.hpp"
#include "selfsense/model_io/model_yaml.hpp"
#include "selfsense/report/diagnose_report.hpp"

namespace selfsense::cli {

using evaluation::ChannelFigures;
using evaluation::field_signals;
using evaluation::FieldSignals;
using evaluation::figures;
using evaluation::report_figures;
using evaluation::report_input;
using evaluation::to_json;
using report::ReportInput;
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

  nlohmann::json j = to_json(result, rec.t);
  const std::vector<ChannelFigures> before = figures(model, rec);
  const std::vector<ChannelFigures> after = figures(result.improved, rec);
  j["fit"] = {{"before", to_json(before)}, {"after", to_json(after)}};
  ReportInput report = report_input(result, rec, model.drive());
  std::vector<ChannelFigures> vb;
  std::vector<ChannelFigures> va;
  if (!opt.validate.empty()) {
    const FieldSignals val = load_signals(opt.validate, model);
    vb = figures(model, val);
    va = figures(result.improved, val);
    j["validation"] = {{"before", to_json(vb)}, {"after", to_json(va)}};
    report.validation_before = report_figures(vb);
    report.validation_after = report_figures(va);
  }
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
