#include "selfsense/runtime/controller.hpp"

#include <algorithm>
#include <cmath>
#include <span>
#include <stdexcept>
#include <utility>

namespace selfsense::runtime {
namespace {

control::Pid::Params limited(control::Pid::Params p, const ControllerConfig& c) {
  p.output_min = c.command_min;
  p.output_max = c.command_max;
  return p;
}

}  // namespace

Feedforward make_feedforward(const ControllerConfig& config,
                             const std::optional<models::SideModel>& actuator, double sample_time) {
  Feedforward ff;
  if (!config.feedforward || !actuator) return ff;
  ff.inverse.emplace(actuator->op, sample_time);
  ff.inverse->set_history(actuator->history);
  ff.compliance = actuator->linear_gains.empty() ? 0.0 : actuator->linear_gains.front();
  ff.strain_offset = actuator->offset;
  return ff;
}

Tuning tuning_of(const ControllerConfig& config) noexcept {
  Tuning t;
  t.position = config.position.gains;
  t.force = config.force.gains;
  t.filters = config.filters;
  t.filter_count = config.filter_count;
  t.command_min = config.command_min;
  t.command_max = config.command_max;
  return t;
}

Controller::Controller(const ControllerConfig& config,
                       const std::optional<models::SideModel>& actuator, double sample_time)
    : config_(config),
      mode_(config.mode),
      position_(limited(config.position, config), sample_time),
      force_(limited(config.force, config), sample_time),
      position_shaper_(config.position_shaper, sample_time),
      force_shaper_(config.force_shaper, sample_time),
      chain_(std::span(config.filters).first(config.filter_count)),
      ff_(make_feedforward(config, actuator, sample_time)) {
  if (!(config.command_min < config.command_max)) {
    throw std::invalid_argument("control.command: min must be < max");
  }
  if (config.force_direction != 1.0 && config.force_direction != -1.0) {
    throw std::invalid_argument("control.force_direction: must be 1 or -1");
  }
  if (config.damping.gain > 0.0) damping_.emplace(config.damping, sample_time);
}

void Controller::swap_feedforward(Feedforward& next) noexcept {
  std::swap(ff_, next);
  if (ff_.inverse) ff_.inverse->reset(last_command_);
}

void Controller::set_feedforward_scales(double response_scale, double compliance_scale) noexcept {
  const auto sane = [](double g) { return std::isfinite(g) && g >= 0.5 && g <= 2.0 ? g : 1.0; };
  ff_response_scale_ = sane(response_scale);
  ff_compliance_scale_ = sane(compliance_scale);
}

double Controller::feedforward(double strain) noexcept {
  if (!ff_.inverse) return 0.0;
  const double target =
      (strain - ff_compliance_scale_ * ff_.compliance * ff_stress_ - ff_.strain_offset) /
      ff_response_scale_;
  const double e = ff_.inverse->input_for(target);
  return std::isfinite(e) ? std::clamp(e, config_.command_min, config_.command_max) : 0.0;
}

double Controller::finish(double u) noexcept {
  const double filtered = chain_.step(u);
  double e = std::isfinite(filtered) ? filtered : last_command_;
  if (e < config_.command_min || e > config_.command_max) ++saturations_;
  e = std::clamp(e, config_.command_min, config_.command_max);
  // The PIDs learn only the clipping, not the filters' dynamics (docs/control.md).
  const double applied_raw = u + (e - filtered);
  if (mode_ == ControlMode::kPosition) position_.track(applied_raw);
  if (mode_ == ControlMode::kForce) force_.track(applied_raw);
  if (ff_.inverse) static_cast<void>(ff_.inverse->step(e));
  last_command_ = e;
  return e;
}

double Controller::step(double setpoint, double s_hat, double t_hat) noexcept {
  return finish(law(setpoint, s_hat, t_hat));
}

double Controller::law(double setpoint, double s_hat, double t_hat) noexcept {
  switch (mode_) {
    case ControlMode::kPosition:
      shaped_ = position_shaper_.step(setpoint);
      return position_.step(shaped_, s_hat, feedforward(shaped_));
    case ControlMode::kForce:
      shaped_ = force_shaper_.step(setpoint);
      return force_.step(config_.force_direction * shaped_, config_.force_direction * t_hat);
    case ControlMode::kOpenLoop:
      shaped_ = position_shaper_.step(setpoint);
      return feedforward(shaped_);
    case ControlMode::kDamping:
      shaped_ = position_shaper_.step(setpoint);
      return feedforward(shaped_) + (damping_ ? damping_->step(s_hat) : 0.0);
  }
  return last_command_;
}

void Controller::arm(double s_hat, double t_hat, double command) noexcept {
  last_command_ = command;
  chain_.reset(command);
  position_shaper_.reset(s_hat);
  force_shaper_.reset(t_hat);
  shaped_ = mode_ == ControlMode::kForce ? t_hat : s_hat;
  if (damping_) damping_->reset(s_hat);
  ff_stress_ = std::isfinite(t_hat) ? t_hat : 0.0;
  position_.reset_bumpless(s_hat, command, s_hat, feedforward(s_hat));
  force_.reset_bumpless(config_.force_direction * t_hat, command);
}

void Controller::set_mode(ControlMode mode, double s_hat, double t_hat, double command) noexcept {
  mode_ = mode;
  arm(s_hat, t_hat, command);
}

bool Controller::tune(const Tuning& tuning) noexcept {
  if (!std::isfinite(tuning.command_min) || !std::isfinite(tuning.command_max) ||
      !(tuning.command_min < tuning.command_max) ||
      tuning.filter_count > control::FilterChain::kMaxSections) {
    return false;
  }
  control::Pid trial_p = position_;
  control::Pid trial_f = force_;
  control::FilterChain trial_chain = chain_;
  if (!trial_p.set_gains(tuning.position) || !trial_f.set_gains(tuning.force) ||
      !trial_p.set_output_limits(tuning.command_min, tuning.command_max) ||
      !trial_f.set_output_limits(tuning.command_min, tuning.command_max) ||
      !trial_chain.assign(std::span(tuning.filters).first(tuning.filter_count), last_command_)) {
    return false;
  }
  position_ = trial_p;
  force_ = trial_f;
  chain_ = trial_chain;
  config_.position.gains = tuning.position;
  config_.force.gains = tuning.force;
  config_.filters = tuning.filters;
  config_.filter_count = tuning.filter_count;
  config_.command_min = tuning.command_min;
  config_.command_max = tuning.command_max;
  return true;
}

}  // namespace selfsense::runtime
