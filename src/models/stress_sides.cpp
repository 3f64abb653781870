#include "selfsense/models/stress_sides.hpp"

#include <limits>
#include <stdexcept>

namespace selfsense::models {
namespace {

const StressHysteresisModel& vectorial_of(const TransducerModel& model) {
  if (!model.vectorial) {
    throw std::invalid_argument("model: the stress-hysteresis kernels need a vectorial section");
  }
  return *model.vectorial;
}

// The model's plain actuator side alone (its plain sensor, if any, runs elsewhere).
TransducerModel plain_actuator_of(const TransducerModel& model) {
  TransducerModel m;
  m.sample_time = model.sample_time;
  m.actuator = model.actuator;
  return m;
}

}  // namespace

StressSidesForward::StressSidesForward(const TransducerModel& model)
    : vectorial_(vectorial_of(model)), plain_(model) {}

StressHysteresisForward::Output StressSidesForward::step(double e, double t) noexcept {
  StressHysteresisForward::Output out = vectorial_.step(e, t);
  const ForwardModel::Output plain = plain_.step(e, t);
  if (plain_.sensor()) out.sensed = plain.sensed;
  if (plain_.actuator()) out.strain = plain.strain;
  return out;
}

std::size_t StressSidesForward::state_size() const noexcept {
  return vectorial_.state_size() + plain_.state_size();
}

void StressSidesForward::save_state(std::span<double> out) const noexcept {
  const std::size_t n = vectorial_.state_size();
  vectorial_.save_state(out.first(n));
  plain_.save_state(out.subspan(n));
}

void StressSidesForward::restore_state(std::span<const double> in) noexcept {
  const std::size_t n = vectorial_.state_size();
  vectorial_.restore_state(in.first(n));
  plain_.restore_state(in.subspan(n));
}

StressSidesReconstructor::StressSidesReconstructor(const TransducerModel& model)
    : plain_strain_(plain_actuator_of(model)) {
  const StressHysteresisModel& v = vectorial_of(model);
  if (v.sensor) {
    solve_.emplace(v);
  } else {
    TransducerModel sensor_only;
    sensor_only.sample_time = model.sample_time;
    sensor_only.sensor = model.sensor;
    if (!sensor_only.sensor) {
      throw std::invalid_argument("stress-hysteresis reconstruction needs a sensor side");
    }
    plain_solve_.emplace(sensor_only);
    strain_.emplace(v);
  }
  has_strain_ = v.actuator.has_value() || model.actuator.has_value();
}

StressSidesReconstructor::Estimate StressSidesReconstructor::step(double e, double d) noexcept {
  if (plain_solve_) {
    const double stress = (d - sensed_response(e)) / sensor_coupling();
    return {stress, strain_at(e, stress), SampleStatus::kOk};
  }
  Estimate out = solve_->step(e, d);
  if (plain_strain_.actuator()) out.strain = plain_strain_.step(e, out.stress).strain;
  return out;
}

double StressSidesReconstructor::strain_at(double e, double t) noexcept {
  if (plain_strain_.actuator()) return plain_strain_.step(e, t).strain;
  return strain_ ? strain_->step(e, t).strain : std::numeric_limits<double>::quiet_NaN();
}

std::size_t StressSidesReconstructor::state_size() const noexcept {
  const std::size_t kernel =
      solve_ ? solve_->state_size() : plain_solve_->state_size() + strain_->state_size();
  return kernel + plain_strain_.state_size();
}

// The field's plays first, then the plain sensor's operator, then the plain actuator's.
void StressSidesReconstructor::save_state(std::span<double> out) const noexcept {
  std::size_t at = 0;
  if (solve_) {
    solve_->save_state(out.first(solve_->state_size()));
    at = solve_->state_size();
  } else {
    strain_->save_state(out.first(strain_->state_size()));
    at = strain_->state_size();
    plain_solve_->save_state(out.subspan(at, plain_solve_->state_size()));
    at += plain_solve_->state_size();
  }
  plain_strain_.save_state(out.subspan(at));
}

void StressSidesReconstructor::restore_state(std::span<const double> in) noexcept {
  std::size_t at = 0;
  if (solve_) {
    solve_->restore_state(in.first(solve_->state_size()));
    at = solve_->state_size();
  } else {
    strain_->restore_state(in.first(strain_->state_size()));
    at = strain_->state_size();
    plain_solve_->restore_state(in.subspan(at, plain_solve_->state_size()));
    at += plain_solve_->state_size();
  }
  plain_strain_.restore_state(in.subspan(at));
}

const operators::RegressorStream& StressSidesReconstructor::stream() const noexcept {
  return solve_ ? solve_->stream() : strain_->stream();
}

operators::RegressorStream& StressSidesReconstructor::stream() noexcept {
  return solve_ ? solve_->stream() : strain_->stream();
}

SideOperator* StressSidesReconstructor::plain_sensor() noexcept {
  return (plain_solve_ && plain_solve_->sensor()) ? &*plain_solve_->sensor() : nullptr;
}

const SideOperator* StressSidesReconstructor::plain_sensor() const noexcept {
  return (plain_solve_ && plain_solve_->sensor()) ? &*plain_solve_->sensor() : nullptr;
}

SideOperator* StressSidesReconstructor::plain_actuator() noexcept {
  return plain_strain_.actuator() ? &*plain_strain_.actuator() : nullptr;
}

const SideOperator* StressSidesReconstructor::plain_actuator() const noexcept {
  return plain_strain_.actuator() ? &*plain_strain_.actuator() : nullptr;
}

}  // namespace selfsense::models
