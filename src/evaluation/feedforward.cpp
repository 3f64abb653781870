#include "selfsense/evaluation/feedforward.hpp"

#include <cmath>
#include <optional>
#include <stdexcept>
#include <utility>
#include <vector>

#include "selfsense/base/format_number.hpp"
#include "selfsense/operators/hysteresis_creep.hpp"

namespace selfsense::evaluation {

FeedforwardRun feedforward(const models::TransducerModel& model, const io::Recording& trajectory,
                           double field_min, double field_max, const std::string& model_source,
                           const std::string& trajectory_source) {
  if (!model.actuator || model.drive() != models::Drive::kField) {
    throw std::invalid_argument(model_source +
                                ": feedforward needs a field-driven model with an actuator side");
  }
  const io::Recording& rec = trajectory;
  const std::optional<models::Geometry>& geometry = model.geometry;
  std::vector<double> desired;
  if (rec.has("S")) {
    const auto s = rec.column("S");
    desired.assign(s.begin(), s.end());
  } else if (rec.has("x") && geometry) {
    for (const double x : rec.column("x"))
      desired.push_back(geometry->strain(x));
  } else {
    throw io::RecordingError(trajectory_source +
                             ": missing the desired strain column 'S' (or 'x' with a geometry)");
  }
  const auto t = rec.column("t");
  const double ts = (t.back() - t.front()) / static_cast<double>(t.size() - 1);
  if (std::abs(ts - model.sample_time) > 0.01 * model.sample_time) {
    throw io::RecordingError(trajectory_source + ": sample time " + base::format_number(ts) +
                             " s differs from the model's " +
                             base::format_number(model.sample_time) + " s");
  }
  const models::SideModel& a = *model.actuator;
  operators::HysteresisCreep op(a.op, a.sample_time);
  op.set_history(a.history);
  operators::HysteresisCreepCompensator compensator(std::move(op), field_min, field_max);
  const double compliance = a.linear_gains.empty() ? 0.0 : a.linear_gains.front();
  std::vector<double> field(desired.size());
  for (std::size_t k = 0; k < desired.size(); ++k) {
    const double stress = rec.has("T") ? rec.column("T")[k] : 0.0;
    field[k] = compensator.step(desired[k] - compliance * stress - a.offset);
  }
  FeedforwardRun run;
  io::Recording& out = run.recording;
  out.set_column("t", {t.begin(), t.end()});
  out.set_column("E", field);
  out.set_column("S_desired", desired);
  if (geometry) {
    std::vector<double> u(field.size());
    for (std::size_t k = 0; k < u.size(); ++k)
      u[k] = geometry->voltage(field[k]);
    out.set_column("u", u);
  }
  run.limited = compensator.saturation_count();
  return run;
}

}  // namespace selfsense::evaluation
