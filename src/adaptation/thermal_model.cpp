#include "selfsense/adaptation/thermal_model.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "selfsense/base/check.hpp"

namespace selfsense::adaptation {

bool ThermalModelConfig::is_valid(const std::string& prefix, std::string* why) const {
  namespace check = base::check;
  const auto key = [&prefix](const char* name) { return prefix + name; };
  return check::non_negative(key("thermal_resistance_k_per_w"), resistance_k_per_w, why) &&
         check::positive(key("thermal_time_constant_s"), time_constant_s, why) &&
         check::finite(key("ambient_degc"), ambient_degc, why) &&
         check::positive(key("stack_volume_m3"), stack_volume_m3, why) &&
         check::positive(key("max_power_w"), max_power_w, why);
}

ThermalModel::ThermalModel(const ThermalModelConfig& config, double sample_time_s)
    : config_{config} {
  std::string why;
  if (!config_.is_valid("adaptation.", &why)) throw std::invalid_argument{why};
  if (!(sample_time_s > 0.0 && std::isfinite(sample_time_s))) {
    throw std::invalid_argument{"adaptation: the sample time must be > 0"};
  }
  ts_ = sample_time_s;
  decay_ = std::exp(-ts_ / config_.time_constant_s);
}

void ThermalModel::step(double field, double sensed, bool accepted) noexcept {
  if (!accepted || !std::isfinite(field) || !std::isfinite(sensed)) {
    has_last_ = false;
    power_w_ = 0.0;
    return;
  }
  power_w_ = 0.0;
  if (has_last_) {
    const double p = config_.stack_volume_m3 * 0.5 * (field + last_e_) * (sensed - last_d_) / ts_;
    if (std::isfinite(p)) power_w_ = std::clamp(p, -config_.max_power_w, config_.max_power_w);
  }
  last_e_ = field;
  last_d_ = sensed;
  has_last_ = true;
}

double ThermalModel::predict(double temperature_degc) const noexcept {
  const double amb = config_.ambient_degc;
  return amb + decay_ * (temperature_degc - amb) +
         (1.0 - decay_) * config_.resistance_k_per_w * power_w_;
}

void ThermalModel::save_state(std::span<double> out) const noexcept {
  if (out.size() < kStateSize) return;
  out[0] = last_e_;
  out[1] = last_d_;
  out[2] = has_last_ ? 1.0 : 0.0;
  out[3] = power_w_;
}

void ThermalModel::restore_state(std::span<const double> in) noexcept {
  if (in.size() < kStateSize) return;
  last_e_ = in[0];
  last_d_ = in[1];
  has_last_ = in[2] != 0.0 && std::isfinite(in[0]) && std::isfinite(in[1]);
  power_w_ =
      std::isfinite(in[3]) ? std::clamp(in[3], -config_.max_power_w, config_.max_power_w) : 0.0;
}

}  // namespace selfsense::adaptation
