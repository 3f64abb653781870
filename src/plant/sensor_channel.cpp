#include "selfsense/plant/sensor_channel.hpp"

#include <algorithm>
#include <cmath>

#include "selfsense/plant/status.hpp"

namespace selfsense::plant {

SensorChannel::SensorChannel(const ChannelConfig& config) : config_{config} {
  if (config_.adc.enabled) {
    max_code_ = std::ldexp(1.0, config_.adc.bits) - 1.0;
    lsb_ = (config_.adc.max - config_.adc.min) / max_code_;
  }
}

void SensorChannel::reset(double x) noexcept {
  line_.fill(x);
  head_ = 0;
}

double SensorChannel::quantise(double y, std::uint32_t* flags) const noexcept {
  if (!config_.adc.enabled) return y;
  double code = std::nearbyint((y - config_.adc.min) / lsb_);
  if (code < 0.0 || code > max_code_) {
    code = std::clamp(code, 0.0, max_code_);
    *flags |= kAdcClipped;
  }
  return config_.adc.min + code * lsb_;
}

double SensorChannel::measure(double x, Random& random, std::uint32_t* flags) noexcept {
  double y = x;
  if (config_.delay_samples > 0) {
    const int size = config_.delay_samples + 1;
    line_[static_cast<std::size_t>(head_)] = x;
    head_ = (head_ + 1) % size;
    y = line_[static_cast<std::size_t>(head_)];  // the oldest: written delay_samples ago
  }
  if (config_.noise_std > 0.0) y += config_.noise_std * random.gaussian();
  return quantise(y, flags);
}

}  // namespace selfsense::plant
