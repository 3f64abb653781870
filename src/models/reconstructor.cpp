#include "selfsense/models/reconstructor.hpp"

#include <cassert>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace selfsense::models {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::optional<SideOperator> make_side(const std::optional<SideModel>& side) {
  if (!side) return std::nullopt;
  return SideOperator(*side);
}

}  // namespace

SideOperator::SideOperator(const SideModel& model)
    : op_(model.op, model.sample_time),
      coupling_(model.linear_gains.empty() ? 0.0 : model.linear_gains.front()),
      offset_(model.offset),
      quadratic_(model.quadratic) {
  op_.set_history(model.history);
}

std::size_t ModelState::size(const std::optional<SideOperator>& a,
                             const std::optional<SideOperator>& b) noexcept {
  return (a ? a->op().state().size() : 0) + (b ? b->op().state().size() : 0);
}

void ModelState::save(const std::optional<SideOperator>& a, const std::optional<SideOperator>& b,
                      std::span<double> out) noexcept {
  assert(out.size() == size(a, b));
  std::size_t at = 0;
  for (const auto* side : {&a, &b}) {
    if (!*side) continue;
    const std::span<const double> s = (*side)->op().state();
    std::copy(s.begin(), s.end(), out.begin() + static_cast<std::ptrdiff_t>(at));
    at += s.size();
  }
}

void ModelState::restore(std::optional<SideOperator>& a, std::optional<SideOperator>& b,
                         std::span<const double> in) noexcept {
  assert(in.size() == size(a, b));
  std::size_t at = 0;
  for (auto* side : {&a, &b}) {
    if (!*side) continue;
    const std::size_t n = (*side)->op().state().size();
    (*side)->op().set_state(in.subspan(at, n));
    at += n;
  }
}

ForwardModel::ForwardModel(const TransducerModel& model)
    : sensor_(make_side(model.sensor)), actuator_(make_side(model.actuator)) {}

ForwardModel::Output ForwardModel::step(double drive, double stress) noexcept {
  Output out{kNaN, kNaN};
  if (sensor_) out.sensed = sensor_->step_unloaded(drive) + sensor_->coupling() * stress;
  if (actuator_) out.strain = actuator_->step_unloaded(drive) + actuator_->coupling() * stress;
  return out;
}

std::size_t ForwardModel::state_size() const noexcept {
  return ModelState::size(sensor_, actuator_);
}
void ForwardModel::save_state(std::span<double> out) const noexcept {
  ModelState::save(sensor_, actuator_, out);
}
void ForwardModel::restore_state(std::span<const double> in) noexcept {
  ModelState::restore(sensor_, actuator_, in);
}

Reconstructor::Reconstructor(const TransducerModel& model)
    : sensor_(make_side(model.sensor)), actuator_(make_side(model.actuator)) {
  if (!sensor_) {
    throw std::invalid_argument("reconstruction needs a sensor side (a model fitted with D)");
  }
  if (!(std::abs(sensor_->coupling()) > 0.0)) {
    throw std::invalid_argument(
        "reconstruction needs a non-zero sensor coupling (a model fitted with a stress channel)");
  }
}

Reconstructor::Estimate Reconstructor::finish(double drive, double sensed,
                                              double response) noexcept {
  Estimate out{(sensed - response) / sensor_->coupling(), kNaN};
  if (actuator_) out.strain = actuator_->step_unloaded(drive) + actuator_->coupling() * out.stress;
  return out;
}

std::size_t Reconstructor::state_size() const noexcept {
  return ModelState::size(sensor_, actuator_);
}
void Reconstructor::save_state(std::span<double> out) const noexcept {
  ModelState::save(sensor_, actuator_, out);
}
void Reconstructor::restore_state(std::span<const double> in) noexcept {
  ModelState::restore(sensor_, actuator_, in);
}

}  // namespace selfsense::models
