#include "selfsense/adaptation/adapted_reconstruction.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace selfsense::adaptation {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The model at the loop's sample time, refused by name where the adaptation cannot run.
models::TransducerModel adaptable(models::TransducerModel model, double sample_time) {
  if (model.drive() != models::Drive::kField) {
    throw std::invalid_argument{"adaptation: needs a field-driven model (E in, D sensed)"};
  }
  if (model.vectorial) {
    throw std::invalid_argument{
        "adaptation: the stress-dependent (vectorial) model is not adapted"};
  }
  if (model.sensed_correction || model.strain_correction) {
    throw std::invalid_argument{"adaptation: a model with diagnosed corrections is not adapted"};
  }
  if (!model.sensor || model.sensor->linear_gains.empty() ||
      model.sensor->linear_gains.front() == 0.0) {
    throw std::invalid_argument{"adaptation: needs a sensor side with a stress coupling"};
  }
  if (!(sample_time >= 0.0)) throw std::invalid_argument{"adaptation: sample time must be >= 0"};
  if (sample_time > 0.0) {
    model.sample_time = sample_time;
    model.sensor->sample_time = sample_time;
    if (model.actuator) model.actuator->sample_time = sample_time;
  }
  return model;
}

// c0: the operator's slope right after a reversal (the PI's linear weight through the
// superposition's).
double linear_weight(const models::SideOperator& side) noexcept {
  const auto& p = side.op().params();
  return p.hysteresis.linear_weight * p.superposition.linear_weight;
}

// The model's fitted coefficients (first order) replace the configured ones per K: the tie of
// the loop to the permittivity, the equivalent temperature's scale and reference.
DriftEstimatorConfig with_coefficients(DriftEstimatorConfig config,
                                       const models::TransducerModel& model) {
  if (!model.temperature || model.temperature->sensor.linear.per_k == 0.0) return config;
  const models::TemperatureCoefficients& t = *model.temperature;
  config.reference_degc = t.reference_degc;
  config.permittivity_per_k = t.sensor.linear.per_k;
  config.loop_per_k = t.sensor.loop.per_k;
  config.coupling_per_k = t.sensor.coupling.per_k;
  config.compliance_per_k = t.actuator.coupling.per_k;
  if (t.increments.fitted()) {  // the estimator learns on increments: read it with theirs
    config.permittivity_per_k = t.increments.linear_per_k;
    config.loop_per_k = t.increments.loop_per_k;
  }
  return config;
}

// The temperature change at which g(dtheta) = 1 + epsilon: the root nearest the first-order one
// (the vertex where there is none).
double temperature_change(const models::TemperaturePolynomial& g, double epsilon) noexcept {
  if (g.per_k2 == 0.0) return g.per_k != 0.0 ? epsilon / g.per_k : 0.0;
  const double disc = g.per_k * g.per_k + 4.0 * g.per_k2 * epsilon;
  if (disc < 0.0) return -g.per_k / (2.0 * g.per_k2);
  const double q = g.per_k + std::copysign(std::sqrt(disc), g.per_k);
  return q != 0.0 ? 2.0 * epsilon / q : 0.0;
}

}  // namespace

SideSplit::SideSplit(const models::SideOperator& side)
    : inverse_shape_{operators::DeadZoneSuperposition(side.op().params().superposition).inverse()} {
}

SideSplit::Parts SideSplit::split(const models::SideOperator& side, double field,
                                  double response) const noexcept {
  const auto& p = side.op().params();
  double creep = 0.0;
  const std::size_t cols = p.creep.eigenvalues.size();
  if (!p.creep.thresholds.empty() && p.creep.thresholds.front() == 0.0) {
    const std::span<const double> state = side.op().state();
    const std::size_t lags = state.size() - p.creep.thresholds.size() * cols;
    for (std::size_t j = 0; j < cols; ++j)
      creep += p.creep.weights[j] * state[lags + j];
  }
  const double linear_in = p.hysteresis.linear_weight * field + creep;
  const double loop =
      p.superposition.linear_weight * (inverse_shape_.evaluate(response) - linear_in);
  return {response - loop, loop};
}

AdaptedReconstruction::AdaptedReconstruction(const models::TransducerModel& model,
                                             const DriftEstimatorConfig& config, double sample_time,
                                             double range_margin)
    : AdaptedReconstruction(adaptable(model, sample_time), config, range_margin, Tag{}) {}

AdaptedReconstruction::AdaptedReconstruction(const models::TransducerModel& model,
                                             const DriftEstimatorConfig& config,
                                             double range_margin, Tag /*unused*/)
    : kernel_(model),
      sensor_split_(*kernel_.sensor()),
      estimator_(with_coefficients(config, model), model.sample_time,
                 linear_weight(*kernel_.sensor())),
      gate_(model.drive_range, model.sensed_range, range_margin),
      last_{0.0, kNaN, models::SampleStatus::kOk} {
  if (kernel_.actuator()) actuator_split_.emplace(*kernel_.actuator());
  if (config.thermal.enabled) thermal_.emplace(config.thermal, model.sample_time);
  coefficients_ = model.temperature;
  identity_ = {model.structure, models::parameter_hash(model), state_size()};
  if (!(range_margin >= 0.0)) {
    throw std::invalid_argument{"adaptation: range_margin must be >= 0"};
  }
  if (config.load_stiffness_ratio > 0.0) {
    if (!kernel_.actuator() || !(kernel_.actuator()->coupling() > 0.0)) {
      throw std::invalid_argument{
          "adaptation.load_stiffness_ratio: needs a model with an actuator side and a compliance"};
    }
    const double r = config.load_stiffness_ratio;
    mount_ratio_ = r;
    mount_kappa_ = r / kernel_.actuator()->coupling();
  }
}

AdaptedReconstruction::Estimate AdaptedReconstruction::step(double field, double sensed,
                                                            bool learn) noexcept {
  const models::SampleStatus status = gate_.check(field, sensed);
  if (status != models::SampleStatus::kOk) {
    counts_.add(status);
    if (held_.valid) {
      const models::SampleStatus previous = last_.status;
      last_ = kernel_step(held_.first, held_.second, false);
      last_.status = previous;
    }
    Estimate out = last_;
    out.status = status;
    return out;
  }
  const Estimate out = kernel_step(field, sensed, learn);
  counts_.add(out.status);
  held_ = {field, sensed, true};
  last_ = out;
  return out;
}

AdaptedReconstruction::Estimate AdaptedReconstruction::kernel_step(double field, double sensed,
                                                                   bool accepted) noexcept {
  models::SideOperator& s = *kernel_.sensor();
  const double fixed_s = s.offset() + s.quadratic() * field * field;  // not scaled by the drift
  const SideSplit::Parts ps = sensor_split_.split(s, field, s.step_unloaded(field) - fixed_s);
  SideSplit::Parts pa{};
  double fixed_a = 0.0;
  if (kernel_.actuator()) {
    models::SideOperator& a = *kernel_.actuator();
    fixed_a = a.offset() + a.quadratic() * field * field;
    pa = actuator_split_->split(a, field, a.step_unloaded(field) - fixed_a);
    actuator_parts_ = pa;
  }
  // The mount's stress from the stack as identified (header comment), for the model's own D.
  const double mount_stress =
      -mount_kappa_ / (1.0 + mount_ratio_) * (fixed_a + pa.linear + pa.loop);
  // The mount's share of D as the stack is now: the free strain, the stiffness ratio and the
  // sensor's coupling with the drift learned so far.
  const Drift now = estimator_.drift();
  const double mount_now =
      -mount_kappa_ / (1.0 + mount_ratio_ * (1.0 + now.compliance)) *
      (fixed_a + (1.0 + now.coupling) * pa.linear + (1.0 + now.loop) * pa.loop);
  const bool measured = measured_degc_ != kNoTemperature;  // learns nothing meanwhile
  estimator_.step(field, sensed - fixed_s - (1.0 + now.coupling) * s.coupling() * mount_now,
                  ps.linear, ps.loop, accepted && !measured);
  const Drift dr = estimator_.drift();
  const Scales g = scales(dr);
  const double unloaded = fixed_s + g.sensor_linear * ps.linear + g.sensor_loop * ps.loop;
  Estimate out{(sensed - unloaded) / (g.sensor_coupling * s.coupling()), kNaN,
               models::SampleStatus::kOk,
               fixed_s + ps.linear + ps.loop + s.coupling() * mount_stress};
  if (kernel_.actuator()) {
    const models::SideOperator& a = *kernel_.actuator();
    out.strain = fixed_a + g.actuator_linear * pa.linear + g.actuator_loop * pa.loop +
                 g.actuator_compliance * a.coupling() * out.stress;
  }
  if (thermal_ && !measured) {  // carry the estimate to the next sample's predicted temperature
    thermal_->step(field, sensed, accepted);
    estimator_.carry(thermal_->predict(dr.temperature_degc) - dr.temperature_degc);
  }
  return out;
}

void AdaptedReconstruction::set_temperature(double degc) noexcept {
  if (!std::isfinite(degc)) return;
  measured_degc_ = degc;
  if (!coefficients_) {
    estimator_.set_temperature(degc);
    return;
  }
  const double dt = degc - coefficients_->reference_degc;  // the fitted sensor side's drift
  if (coefficients_->increments.fitted()) {                // as the estimator reads it (increments)
    estimator_.set_drift(coefficients_->increments.linear_per_k * dt,
                         coefficients_->increments.loop_per_k * dt);
    return;
  }
  estimator_.set_drift(coefficients_->sensor.linear.scale(dt) - 1.0,
                       coefficients_->sensor.loop.scale(dt) - 1.0);
}

AdaptedReconstruction::Scales AdaptedReconstruction::scales(const Drift& dr) const noexcept {
  if (coefficients_ && measured_degc_ != kNoTemperature) {
    const double dt = measured_degc_ - coefficients_->reference_degc;
    const models::SideTemperature& s = coefficients_->sensor;
    const models::SideTemperature& a = coefficients_->actuator;
    return {s.linear.scale(dt), s.loop.scale(dt), s.coupling.scale(dt),
            a.linear.scale(dt), a.loop.scale(dt), a.coupling.scale(dt)};
  }
  if (coefficients_ && coefficients_->increments.fitted()) {
    // Learned on increments, read as a temperature; every part at it from the level fit.
    const double dt = dr.permittivity / coefficients_->increments.linear_per_k;
    const models::SideTemperature& s = coefficients_->sensor;
    const models::SideTemperature& a = coefficients_->actuator;
    return {s.linear.scale(dt), s.loop.scale(dt), s.coupling.scale(dt),
            a.linear.scale(dt), a.loop.scale(dt), a.coupling.scale(dt)};
  }
  if (coefficients_) {  // the learned sensor side; the rest at the equivalent temperature
    const double dt = temperature_change(coefficients_->sensor.linear, dr.permittivity);
    const models::SideTemperature& s = coefficients_->sensor;
    const models::SideTemperature& a = coefficients_->actuator;
    return {1.0 + dr.permittivity, 1.0 + dr.loop,    s.coupling.scale(dt),
            a.linear.scale(dt),    a.loop.scale(dt), a.coupling.scale(dt)};
  }
  return {1.0 + dr.permittivity, 1.0 + dr.loop, 1.0 + dr.coupling,
          1.0 + dr.coupling,     1.0 + dr.loop, 1.0 + dr.compliance};
}

AdaptedReconstruction::FeedforwardScales AdaptedReconstruction::feedforward_scales()
    const noexcept {
  if (!kernel_.actuator()) return {};
  const Scales g = scales(estimator_.drift());
  const double l = actuator_parts_.linear;
  const double h = actuator_parts_.loop;
  const double sum = l + h;
  if (!(std::abs(sum) > 1e-3 * (std::abs(l) + std::abs(h)))) return {1.0, g.actuator_compliance};
  return {(g.actuator_linear * l + g.actuator_loop * h) / sum, g.actuator_compliance};
}

Drift AdaptedReconstruction::drift() const noexcept {
  Drift dr = estimator_.drift();
  if (coefficients_ && !coefficients_->increments.fitted()) {
    dr.temperature_degc =
        measured_degc_ != kNoTemperature
            ? measured_degc_
            : coefficients_->reference_degc +
                  temperature_change(coefficients_->sensor.linear, dr.permittivity);
  }
  return dr;
}

std::size_t AdaptedReconstruction::state_size() const noexcept {
  return kernel_.state_size() + DriftEstimator::state_size() +
         (thermal_ ? ThermalModel::state_size() : 0U);
}

bool AdaptedReconstruction::save_state(std::span<double> out) const noexcept {
  if (out.size() != state_size()) return false;
  kernel_.save_state(out.first(kernel_.state_size()));
  estimator_.save_state(out.subspan(kernel_.state_size(), DriftEstimator::state_size()));
  if (thermal_) {
    thermal_->save_state(out.subspan(kernel_.state_size() + DriftEstimator::state_size()));
  }
  return true;
}

bool AdaptedReconstruction::restore_state(std::span<const double> in) noexcept {
  if (in.size() != state_size()) return false;
  kernel_.restore_state(in.first(kernel_.state_size()));
  estimator_.restore_state(in.subspan(kernel_.state_size(), DriftEstimator::state_size()));
  if (thermal_) {
    thermal_->restore_state(in.subspan(kernel_.state_size() + DriftEstimator::state_size()));
  }
  return true;
}

models::SavedState AdaptedReconstruction::make_saved_state() const {
  return {identity_, std::vector<double>(identity_.state_size, 0.0)};
}

bool AdaptedReconstruction::save_state(models::SavedState& out) const noexcept {
  if (out.values.size() != identity_.state_size) return false;
  out.identity = identity_;
  return save_state(std::span<double>(out.values));
}

models::RestoreResult AdaptedReconstruction::restore_state(const models::SavedState& in) noexcept {
  if (in.identity.structure != identity_.structure ||
      in.identity.parameter_hash != identity_.parameter_hash) {
    return models::RestoreResult::kWrongModel;
  }
  if (in.identity.state_size != identity_.state_size || in.values.size() != identity_.state_size) {
    return models::RestoreResult::kWrongSize;
  }
  restore_state(std::span<const double>(in.values));
  return models::RestoreResult::kOk;
}

}  // namespace selfsense::adaptation
