// `selfsense feedforward`: inverse compensation (the paper's reference [11]). From a desired
// strain trajectory, computes the field that makes the modelled actuator follow it:
//   E = Ga^-1[S_desired - sE * T - S0]
// with the hysteresis-creep compensator, limited to the amplifier's field range.
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "selfsense/base/format_number.hpp"
#include "selfsense/io/recording.hpp"
#include "selfsense/model_io/model_yaml.hpp"
#include "selfsense/operators/hysteresis_creep.hpp"
#include "selfsense/operators/parameter_error.hpp"

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
  if (!model.actuator || model.drive() != models::Drive::kField) {
    throw std::invalid_argument(opt.model.string() +
                                ": feedforward needs a field-driven model with an actuator side");
  }
  io::Recording rec = io::read_recording_csv(opt.trajectory, io::ReadOptions{{"t"}});
  const std::optional<models::Geometry>& geometry = model.geometry;
  // The trajectory names the strain to follow (S, or x with the geometry) and may name T.
  std::vector<double> desired;
  if (rec.has("S")) {
    const auto s = rec.column("S");
    desired.assign(s.begin(), s.end());
  } else if (rec.has("x") && geometry) {
    for (const double x : rec.column("x"))
      desired.push_back(geometry->strain(x));
  } else {
    throw io::RecordingError(opt.trajectory.string() +
                             ": missing the desired strain column 'S' (or 'x' with a geometry)");
  }
  const auto t = rec.column("t");
  const double ts = (t.back() - t.front()) / static_cast<double>(t.size() - 1);
  if (std::abs(ts - model.sample_time) > 0.01 * model.sample_time) {
    throw io::RecordingError(opt.trajectory.string() + ": sample time " + base::format_number(ts) +
                             " s differs from the model's " +
                             base::format_number(model.sample_time) + " s");
  }
  const models::SideModel& a = *model.actuator;
  operators::HysteresisCreep op(a.op, a.sample_time);
  op.set_history(a.history);
  operators::HysteresisCreepCompensator compensator(std::move(op), opt.field_min, opt.field_max);
  const double compliance = a.linear_gains.empty() ? 0.0 : a.linear_gains.front();
  std::vector<double> field(desired.size());
  for (std::size_t k = 0; k < desired.size(); ++k) {
    const double stress = rec.has("T") ? rec.column("T")[k] : 0.0;
    field[k] = compensator.step(desired[k] - compliance * stress - a.offset);
  }
  io::Recording out;
  out.comments.push_back("selfsense feedforward with model " + opt.model.string() + " for " +
                         opt.trajectory.string());
  out.set_column("t", {t.begin(), t.end()});
  out.set_column("E", field);
  out.set_column("S_desired", desired);
  if (geometry) {
    std::vector<double> u(field.size());
    for (std::size_t k = 0; k < u.size(); ++k)
      u[k] = geometry->voltage(field[k]);
    out.set_column("u", u);
  }
  io::write_recording_csv(out, opt.out);
  std::printf("wrote %s (%zu samples, %zu limited to the field range)\n", opt.out.string().c_str(),
              field.size(), compensator.saturation_count());
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
