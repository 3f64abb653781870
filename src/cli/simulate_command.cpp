// `selfsense simulate` and `selfsense reconstruct` (docs/recording-format.md): run a model over a
// recording and write its outputs beside the recorded columns.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "commands.hpp"
#include "selfsense/base/format_number.hpp"
#include "selfsense/evaluation/field_signals.hpp"
#include "selfsense/evaluation/model_runs.hpp"
#include "selfsense/identification/fit_quality.hpp"
#include "selfsense/io/recording.hpp"
#include "selfsense/model_io/model_yaml.hpp"

namespace selfsense::cli {

using evaluation::AdaptedRuns;
using evaluation::describe;
using evaluation::field_signals;
using evaluation::FieldSignals;
using evaluation::ModelRuns;
using evaluation::run_adapted;
using evaluation::run_model;
using models::can_reconstruct;
namespace {

struct RunOptions {
  std::filesystem::path model{};
  std::filesystem::path recording{};
  std::filesystem::path out{};
  bool adapt{false};                 // reconstruct: estimate the drift online (docs/adaptation.md)
  std::string temperature_column{};  // reconstruct: the recorded temperature [degC] to use
};

// `reconstruct --adapt`: T_hat and S_hat with the equivalent temperature (temp_equivalent
// [degC]) and the permittivity drift (permittivity_drift [1]) beside them.
void write_adapted(const models::TransducerModel& model, const FieldSignals& signals,
                   const std::vector<double>& temperature, io::Recording& rec) {
  AdaptedRuns runs = run_adapted(model, signals, temperature);
  rec.set_column("T_hat", std::move(runs.stress_hat));
  if (!runs.strain_hat.empty()) rec.set_column("S_hat", std::move(runs.strain_hat));
  rec.set_column("estimate_status", std::move(runs.estimate_status));
  rec.set_column("temp_equivalent", std::move(runs.temp_equivalent));
  rec.set_column("permittivity_drift", std::move(runs.permittivity_drift));
  std::printf(
      "adaptation: %zu updates; at the end permittivity %+.3f %%, loop %+.3f %%, "
      "equivalent temperature %.2f degC%s\n",
      runs.updates, 100.0 * runs.last.permittivity, 100.0 * runs.last.loop,
      runs.last.temperature_degc, temperature.empty() ? "" : " (from the recorded temperature)");
  std::printf("samples: %s\n", describe(runs.counts).c_str());
}

// Says what a user must know about the run: the rate it ran at and every rejected sample.
void report(const ModelRuns& runs, const models::StatusCounts& counts) {
  if (runs.rediscretised) {
    std::printf("model re-discretised for the recording's sample time %s s\n",
                base::format_number(runs.sample_time).c_str());
  }
  std::printf("samples: %s\n", describe(counts).c_str());
}

// Where the recording holds the reference (a bench or plant recording): the estimates' figures
// (docs/recording-format.md: nrmse and max relative to the reference's range), and the equivalent
// temperature's error against a recorded temperature.
void report_figures(const io::Recording& rec, const FieldSignals& signals) {
  const auto print = [](const char* name, std::span<const double> reference,
                        std::span<const double> estimate) {
    const identification::FitQuality q = identification::fit_quality(reference, estimate);
    std::printf("%s: nrmse %.3f %%, max %.3f %% (against the recorded reference)\n", name,
                100.0 * q.nrmse, 100.0 * q.max);
  };
  if (!signals.stress.empty() && rec.has("T_hat"))
    print("T_hat", signals.stress, rec.column("T_hat"));
  if (!signals.s.empty() && rec.has("S_hat")) print("S_hat", signals.s, rec.column("S_hat"));
  if (rec.has("temp") && rec.has("temp_equivalent")) {
    const std::span<const double> truth = rec.column("temp");
    const std::span<const double> eq = rec.column("temp_equivalent");
    double sq = 0.0;
    double worst = 0.0;
    for (std::size_t k = 0; k < truth.size(); ++k) {
      const double e = eq[k] - truth[k];
      sq += e * e;
      worst = std::max(worst, std::abs(e));
    }
    std::printf("temp_equivalent: error %.2f K RMS, %.2f K max (against the column temp)\n",
                std::sqrt(sq / static_cast<double>(std::max<std::size_t>(truth.size(), 1))), worst);
  }
}

void run(const RunOptions& opt, bool reconstruct) {
  const models::TransducerModel model = models::load_model(opt.model);
  io::Recording rec = io::read_recording_csv(opt.recording, io::ReadOptions{{"t"}});
  FieldSignals signals = field_signals(rec, opt.recording.string(), model.geometry, model.drive());
  std::vector<double> temperature{};
  if (!opt.temperature_column.empty()) {
    const std::span<const double> column = rec.column(opt.temperature_column);
    temperature.assign(column.begin(), column.end());
    signals.temp = temperature;
  }
  if (reconstruct) {
    if (signals.sensed(model.drive()).empty()) {
      throw io::RecordingError(signals.source + ": reconstruction needs the sensed channel (" +
                               (model.drive() == models::Drive::kField ? "D or q)" : "E or u)"));
    }
    if (!can_reconstruct(model)) {
      throw io::RecordingError(opt.model.string() +
                               ": the model cannot reconstruct stress (no sensor side with a "
                               "stress coupling: identify it from a recording with T or F)");
    }
    if (opt.adapt) {
      write_adapted(model, signals, temperature, rec);
    } else {
      const ModelRuns runs = run_model(model, signals, false, true);
      rec.set_column("T_hat", runs.stress_hat);
      if (!runs.strain_hat.empty()) rec.set_column("S_hat", runs.strain_hat);
      rec.set_column("estimate_status", runs.estimate_status);
      report(runs, runs.estimate_counts);
    }
    report_figures(rec, signals);
  } else {
    const ModelRuns runs = run_model(model, signals, true, false);
    const bool field = model.drive() == models::Drive::kField;
    if (!runs.sensed.empty()) rec.set_column(field ? "D_model" : "E_model", runs.sensed);
    if (!runs.strain.empty()) rec.set_column("S_model", runs.strain);
    rec.set_column("model_status", runs.forward_status);
    report(runs, runs.forward_counts);
  }
  rec.comments.push_back(std::string("selfsense ") + (reconstruct ? "reconstruct" : "simulate") +
                         (opt.adapt ? " --adapt" : "") + " with model " + opt.model.string());
  io::write_recording_csv(rec, opt.out);
  std::printf("wrote %s (%zu samples)\n", opt.out.string().c_str(), rec.rows());
}

void add(CLI::App& app, const char* name, const char* help, bool reconstruct) {
  auto opt = std::make_shared<RunOptions>();
  CLI::App* cmd = app.add_subcommand(name, help);
  cmd->add_option("--model", opt->model, "Model (YAML)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--recording", opt->recording, "Recording (CSV)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", opt->out, "Output recording (CSV)")->required();
  if (reconstruct) {
    cmd->add_flag("--adapt", opt->adapt,
                  "Estimate the sensor side's drift online from E and D (docs/adaptation.md); "
                  "writes temp_equivalent and permittivity_drift too");
    cmd->add_option("--temperature-column", opt->temperature_column,
                    "Recorded temperature column [degC]: with --adapt the drift follows it, "
                    "without it feeds the model's temperature corrections");
  }
  cmd->callback([opt, reconstruct] { run(*opt, reconstruct); });
}

}  // namespace

void add_simulate_command(CLI::App& app) {
  add(app, "simulate", "Drive the model with the recorded E (and T); write D_model, S_model",
      false);
}

void add_reconstruct_command(CLI::App& app) {
  add(app, "reconstruct", "Self-sensing: from recorded E and D write T_hat and S_hat", true);
}

}  // namespace selfsense::cli
