// `selfsense feedforward`: inverse compensation (evaluation/feedforward.hpp): the field that
// makes the modelled actuator follow a desired strain trajectory, limited to the amplifier's
// field range.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>

#include "commands.hpp"
#include "selfsense/evaluation/feedforward.hpp"
#include "selfsense/io/recording.hpp"
#include "selfsense/model_io/model_yaml.hpp"

namespace selfsense::cli {
namespace {

struct FeedforwardOptions {
  std::filesystem::path model{};
  std::filesystem::path trajectory{};
  std::filesystem::path out{};
  double field_min{-std::numeric_limits<double>::max()};
  double field_max{std::numeric_limits<double>::max()};
};

void run_feedforward(const FeedforwardOptions& opt) {
  const models::TransducerModel model = models::load_model(opt.model);
  const io::Recording trajectory = io::read_recording_csv(opt.trajectory, io::ReadOptions{{"t"}});
  evaluation::FeedforwardRun run = evaluation::feedforward(
      model, trajectory, opt.field_min, opt.field_max, opt.model.string(), opt.trajectory.string());
  run.recording.comments.push_back("selfsense feedforward with model " + opt.model.string() +
                                   " for " + opt.trajectory.string());
  io::write_recording_csv(run.recording, opt.out);
  std::printf("wrote %s (%zu samples, %zu limited to the field range)\n", opt.out.string().c_str(),
              run.recording.rows(), run.limited);
}

}  // namespace

void add_feedforward_command(CLI::App& app) {
  auto opt = std::make_shared<FeedforwardOptions>();
  CLI::App* cmd = app.add_subcommand(
      "feedforward", "Inverse compensation: the field that makes the actuator follow a strain");
  cmd->add_option("--model", opt->model, "Model (YAML) with an actuator side")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--trajectory", opt->trajectory, "Desired strain: CSV with t, S (optional T)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", opt->out, "Field trajectory to write (CSV: t, E, S_desired)")
      ->required();
  cmd->add_option("--field-min", opt->field_min, "Lowest field the amplifier gives [V/m]");
  cmd->add_option("--field-max", opt->field_max, "Highest field the amplifier gives [V/m]");
  cmd->callback([opt] { run_feedforward(*opt); });
}

}  // namespace selfsense::cli
