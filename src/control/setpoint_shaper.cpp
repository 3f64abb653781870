#include "selfsense/control/setpoint_shaper.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "selfsense/control/parameter_error.hpp"

namespace selfsense::control {

bool SetpointShaper::Params::is_valid(double sample_time, std::string* why) const {
  if (!check::positive("SetpointShaper.sample_time", sample_time, why) ||
      !check::non_negative("SetpointShaper.slew_rate", slew_rate, why)) {
    return false;
  }
  if (filter == Filter::kNone) return true;
  return check::positive("SetpointShaper.time_constant", time_constant, why);
}

SetpointShaper::SetpointShaper(const Params& params, double sample_time) : params_(params) {
  std::string why;
  require_valid(params_.is_valid(sample_time, &why), why);
  max_step_ = params_.slew_rate * sample_time;
  if (params_.filter != Filter::kNone) {
    lag_gain_ = -std::expm1(-sample_time / params_.time_constant);
  }
}

double SetpointShaper::step(double target) noexcept {
  if (max_step_ > 0.0) {
    slewed_ += std::clamp(target - slewed_, -max_step_, max_step_);
  } else {
    slewed_ = target;
  }
  switch (params_.filter) {
    case Filter::kNone:
      lagged_ = slewed_;
      output_ = slewed_;
      break;
    case Filter::kFirstOrder:
      lagged_ += lag_gain_ * (slewed_ - lagged_);
      output_ = lagged_;
      break;
    case Filter::kSecondOrder:
      lagged_ += lag_gain_ * (slewed_ - lagged_);
      output_ += lag_gain_ * (lagged_ - output_);
      break;
  }
  return output_;
}

void SetpointShaper::reset(double value) noexcept {
  slewed_ = value;
  lagged_ = value;
  output_ = value;
}

void SetpointShaper::save_state(std::span<double> out) const noexcept {
  assert(out.size() >= kStateSize);
  out[0] = slewed_;
  out[1] = lagged_;
  out[2] = output_;
}

void SetpointShaper::restore_state(std::span<const double> in) noexcept {
  assert(in.size() >= kStateSize);
  slewed_ = in[0];
  lagged_ = in[1];
  output_ = in[2];
}

}  // namespace selfsense::control
