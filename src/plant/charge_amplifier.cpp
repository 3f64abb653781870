#include "selfsense/plant/charge_amplifier.hpp"

#include <cmath>

namespace selfsense::plant {

ChargeAmplifier::ChargeAmplifier(const ChargeAmplifierConfig& config, double sample_time_s)
    : config_{config}, ts_{sample_time_s} {
  if (config_.leakage_enabled) {
    const double ratio = sample_time_s / config_.leakage_tau_s;
    g_ = std::exp(-ratio);
    gain_ = -std::expm1(-ratio) / ratio;
  }
}

void ChargeAmplifier::reset(double q) noexcept {
  q_last_ = q;
  q_m_ = 0.0;
  q_off_ = config_.drift_enabled ? config_.offset_c : 0.0;
}

double ChargeAmplifier::update(double q, Random& random) noexcept {
  q_m_ = g_ * q_m_ + gain_ * (q - q_last_);
  q_last_ = q;
  const double out = q_m_ + q_off_;
  // The offset for the next sample, so that q_off[0] = offset and q_off(t) = offset + drift t.
  if (config_.drift_enabled) {
    q_off_ += config_.drift_c_per_s * ts_ +
              config_.random_walk_c_per_sqrt_s * std::sqrt(ts_) * random.gaussian();
  }
  return out;
}

}  // namespace selfsense::plant
