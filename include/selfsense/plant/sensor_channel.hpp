// One measured channel (ChannelConfig in config.hpp): a delay line of delay_samples, additive
// Gaussian noise and an ADC with `bits` over [min, max]:
//   y[k] = x[k - delay] + noise_std n[k]
//   code = clamp(round((y - min) / lsb), 0, 2^bits - 1),  lsb = (max - min) / (2^bits - 1),
//   measured = min + code lsb   (clipping sets StatusFlag::adc_clipped)
// Value type without heap memory; measure() is real-time safe.
#pragma once

#include <array>
#include <cstdint>

#include "selfsense/plant/config.hpp"
#include "selfsense/plant/random.hpp"

namespace selfsense::plant {

class SensorChannel final {
 public:
  SensorChannel() = default;
  explicit SensorChannel(const ChannelConfig& config);
  void reset(double x) noexcept;
  double measure(double x, Random& random, std::uint32_t* flags) noexcept;
  [[nodiscard]] double quantise(double y, std::uint32_t* flags) const noexcept;
  [[nodiscard]] double lsb() const noexcept { return lsb_; }
  // A value beyond the converter's range, as a broken front end delivers it.
  [[nodiscard]] double out_of_range_value() const noexcept {
    return config_.adc.max + (config_.adc.max - config_.adc.min);
  }

 private:
  ChannelConfig config_{};
  double lsb_{0.0};
  double max_code_{0.0};
  std::array<double, kMaxDelaySamples + 1> line_{};
  int head_{0};
};

}  // namespace selfsense::plant
