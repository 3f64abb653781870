// `selfsense simulate` and `selfsense reconstruct` (contracts.md): run a model over a recording
// and write its outputs beside the recorded columns.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "commands.hpp"
#include "field_signals.hpp"
#include "model_runs.hpp"
#include "selfsense/io/recording.hpp"
#include "selfsense/model_io/model_yaml.hpp"
#include "selfsense/operators/parameter_error.hpp"

namespace selfsense::cli {
namespace {

struct RunOptions {
  std::filesystem::path model{};
  std::filesystem::path recording{};
  std::filesystem::path out{};
};

// Says what a user must know about the run: the rate it ran at and every rejected sample.
void report(const ModelRuns& runs, const models::StatusCounts& counts) {
  if (runs.rediscretised) {
    std::printf("model re-discretised for the recording's sample time %s s\n",
                operators::format_number(runs.sample_time).c_str());
  }
  std::printf("samples: %s\n", describe(counts).c_str());
}

void run(const RunOptions& opt, bool reconstruct) {
  const models::TransducerModel model = models::load_model(opt.model);
  io::Recording rec = io::read_recording_csv(opt.recording, io::ReadOptions{{"t"}});
  const FieldSignals signals =
      field_signals(rec, opt.recording.string(), model.geometry, model.drive());
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
    const ModelRuns runs = run_model(model, signals, false, true);
    rec.set_column("T_hat", runs.stress_hat);
    if (!runs.strain_hat.empty()) rec.set_column("S_hat", runs.strain_hat);
    rec.set_column("estimate_status", runs.estimate_status);
    report(runs, runs.estimate_counts);
  } else {
    const ModelRuns runs = run_model(model, signals, true, false);
    const bool field = model.drive() == models::Drive::kField;
    if (!runs.sensed.empty()) rec.set_column(field ? "D_model" : "E_model", runs.sensed);
    if (!runs.strain.empty()) rec.set_column("S_model", runs.strain);
    rec.set_column("model_status", runs.forward_status);
    report(runs, runs.forward_counts);
  }
  rec.comments.push_back(std::string("selfsense ") + (reconstruct ? "reconstruct" : "simulate") +
                         " with model " + opt.model.string());
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
