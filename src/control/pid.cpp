#include "selfsense/control/pid.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "selfsense/base/format_number.hpp"
#include "selfsense/control/parameter_error.hpp"

namespace selfsense::control {
namespace {

bool gains_usable(const Pid::Gains& g, double filter_n) noexcept {
  const bool finite_non_negative = std::isfinite(g.kp) && std::isfinite(g.ki) &&
                                   std::isfinite(g.kd) && g.kp >= 0.0 && g.ki >= 0.0 && g.kd >= 0.0;
  return finite_non_negative && !(filter_n > 0.0 && g.kp == 0.0 && g.kd > 0.0);
}

}  // namespace

bool Pid::Params::is_valid(double sample_time, std::string* why) const {
  if (!check::positive("Pid.sample_time", sample_time, why) ||
      !check::non_negative("Pid.gains.kp", gains.kp, why) ||
      !check::non_negative("Pid.gains.ki", gains.ki, why) ||
      !check::non_negative("Pid.gains.kd", gains.kd, why) ||
      !check::finite("Pid.setpoint_weight", setpoint_weight, why) ||
      !check::non_negative("Pid.derivative_filter_time", derivative_filter_time, why) ||
      !check::non_negative("Pid.derivative_filter_n", derivative_filter_n, why) ||
      !check::non_negative("Pid.tracking_time", tracking_time, why)) {
    return false;
  }
  if (derivative_filter_n > 0.0 && gains.kp == 0.0 && gains.kd > 0.0) {
    return check::fail("Pid.derivative_filter_n",
                       "needs Pid.gains.kp > 0 (Tf = kd / (kp N)); give derivative_filter_time",
                       why);
  }
  if (std::isnan(output_min) || std::isnan(output_max) || !(output_max > output_min)) {
    return check::fail("Pid.output_max",
                       base::format_number(output_max) +
                           " must be > Pid.output_min = " + base::format_number(output_min),
                       why);
  }
  if (tracking_time > 0.0 && tracking_time < sample_time) {
    return check::fail(
        "Pid.tracking_time",
        base::format_number(tracking_time) +
            " must be 0 (off) or >= sample_time = " + base::format_number(sample_time),
        why);
  }
  return true;
}

Pid::Pid(const Params& params, double sample_time) : params_(params), ts_(sample_time) {
  std::string why;
  require_valid(params_.is_valid(sample_time, &why), why);
  track_gain_ = params_.tracking_time > 0.0 ? ts_ / params_.tracking_time : 1.0;
  update_coefficients();
}

double Pid::filter_time(const Gains& gains) const noexcept {
  if (params_.derivative_filter_n > 0.0) {
    return gains.kd > 0.0 ? gains.kd / (gains.kp * params_.derivative_filter_n) : 0.0;
  }
  return params_.derivative_filter_time;
}

void Pid::update_coefficients() noexcept {
  const double tf = filter_time(params_.gains);
  ad_ = tf / (tf + ts_);
  bd_ = params_.gains.kd / (tf + ts_);
}

double Pid::step(double setpoint, double measurement, double feedforward) noexcept {
  if (!primed_) {
    last_measurement_ = measurement;
    primed_ = true;
  }
  const Gains& g = params_.gains;
  const double error = setpoint - measurement;
  const double proportional = g.kp * (params_.setpoint_weight * setpoint - measurement);
  derivative_ = ad_ * derivative_ - bd_ * (measurement - last_measurement_);
  const double unlimited = proportional + integral_ + derivative_ + feedforward;
  output_ = std::clamp(unlimited, params_.output_min, params_.output_max);

  const bool pushing_out = (unlimited > params_.output_max && error > 0.0) ||
                           (unlimited < params_.output_min && error < 0.0);
  if (!(params_.conditional_integration && pushing_out)) integral_ += g.ki * ts_ * error;
  if (params_.tracking_time > 0.0) integral_ += track_gain_ * (output_ - unlimited);

  last_measurement_ = measurement;
  last_setpoint_ = setpoint;
  return output_;
}

void Pid::track(double applied_output) noexcept {
  integral_ += track_gain_ * (applied_output - output_);
  output_ = applied_output;
}

bool Pid::set_gains(const Gains& gains) noexcept {
  if (!gains_usable(gains, params_.derivative_filter_n)) return false;
  const double old_kp = params_.gains.kp;
  const double old_ad = ad_;
  params_.gains = gains;
  update_coefficients();
  if (primed_) {
    // The next output at unchanged inputs is kp (b r - y) + I + ad D + u_ff: keep it.
    const double weighted_error = params_.setpoint_weight * last_setpoint_ - last_measurement_;
    integral_ += (old_kp - gains.kp) * weighted_error + (old_ad - ad_) * derivative_;
  }
  return true;
}

bool Pid::set_output_limits(double output_min, double output_max) noexcept {
  if (std::isnan(output_min) || std::isnan(output_max) || !(output_max > output_min)) return false;
  params_.output_min = output_min;
  params_.output_max = output_max;
  return true;
}

void Pid::reset() noexcept {
  integral_ = 0.0;
  derivative_ = 0.0;
  last_measurement_ = 0.0;
  last_setpoint_ = 0.0;
  output_ = 0.0;
  primed_ = false;
}

void Pid::reset_bumpless(double measurement, double current_output, double setpoint,
                         double feedforward) noexcept {
  derivative_ = 0.0;
  last_measurement_ = measurement;
  last_setpoint_ = setpoint;
  output_ = current_output;
  primed_ = true;
  integral_ = current_output - feedforward -
              params_.gains.kp * (params_.setpoint_weight * setpoint - measurement);
}

double Pid::derivative_nyquist_gain() const noexcept {
  return 2.0 * bd_ / (1.0 + ad_);
}

void Pid::save_state(std::span<double> out) const noexcept {
  assert(out.size() >= kStateSize);
  out[0] = integral_;
  out[1] = derivative_;
  out[2] = last_measurement_;
  out[3] = last_setpoint_;
  out[4] = output_;
  out[5] = primed_ ? 1.0 : 0.0;
}

void Pid::restore_state(std::span<const double> in) noexcept {
  assert(in.size() >= kStateSize);
  integral_ = in[0];
  derivative_ = in[1];
  last_measurement_ = in[2];
  last_setpoint_ = in[3];
  output_ = in[4];
  primed_ = in[5] != 0.0;
}

}  // namespace selfsense::control
