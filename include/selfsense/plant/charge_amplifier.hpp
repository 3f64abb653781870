// Charge amplifier measuring the stack charge (ChargeAmplifierConfig in config.hpp):
//   leakage: q_m[k] = g q_m[k-1] + (q[k] - q[k-1]) (1 - g) / (Ts / tau),  g = exp(-Ts / tau)
//            (exact for a current constant over the sample); without leakage q_m = q - q(0).
//   drift:   q_off[k] = q_off[k-1] + drift Ts + sigma sqrt(Ts) n[k],  q_off[0] = offset
// Returns q_m[k] + q_off[k]. update() is real-time safe.
#pragma once

#include "selfsense/plant/config.hpp"
#include "selfsense/plant/random.hpp"

namespace selfsense::plant {

class ChargeAmplifier final {
 public:
  ChargeAmplifier() = default;
  ChargeAmplifier(const ChargeAmplifierConfig& config, double sample_time_s);
  void reset(double q) noexcept;
  double update(double q, Random& random) noexcept;

 private:
  ChargeAmplifierConfig config_{};
  double ts_{0.0};
  double g_{1.0};
  double gain_{1.0};
  double q_last_{0.0};
  double q_m_{0.0};
  double q_off_{0.0};
};

}  // namespace selfsense::plant
