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

// The model's creep is discretised for its sample time: the recording must match it.
void check_sample_time(const models::TransducerModel& model, const FieldSignals& signals) {
  if (std::abs(signals.sample_time - model.sample_time) > 0.01 * model.sample_time) {
    throw io::RecordingError(
        signals.source + ": sample time " + operators::format_number(signals.sample_time) +
        " s differs from the model's " + operators::format_number(model.sample_time) + " s");
  }
}

void run(const RunOptions& opt, bool reconstruct) {
  const models::TransducerModel model = models::load_model(opt.model);
  io::Recording rec = io::read_recording_csv(opt.recording, io::ReadOptions{{"t"}});
  const FieldSignals signals =
      field_signals(rec, opt.recording.string(), model.geometry, model.drive());
  check_sample_time(model, signals);
  if (reconstruct) {
    if (signals.sensed(model.drive()).empty()) {
      throw io::RecordingError(signals.source + ": reconstruction needs the sensed channel (" +
                               (model.drive() == models::Drive::kField ? "D or q)" : "E or u)"));
    }
    const ModelRuns runs = run_model(model, signals, false, true);
    rec.set_column("T_hat", runs.stress_hat);
    if (!runs.strain_hat.empty()) rec.set_column("S_hat", runs.strain_hat);
  } else {
    const ModelRuns runs = run_model(model, signals, true, false);
    const bool field = model.drive() == models::Drive::kField;
    if (!runs.sensed.empty()) rec.set_column(field ? "D_model" : "E_model", runs.sensed);
    if (!runs.strain.empty()) rec.set_column("S_model", runs.strain);
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
