#include "selfsense/drivers/spi/dac8563.hpp"

#include <cmath>

namespace selfsense::drivers::spi::dac8563 {

Code code_of(double volts, double full_scale_v) noexcept {
  const double c = std::round(volts / full_scale_v * 65536.0);
  if (!(c >= 0.0)) return {0, true};  // below zero scale, or NaN
  if (c > 65535.0) return {65535, true};
  return {static_cast<std::uint16_t>(c), false};
}

}  // namespace selfsense::drivers::spi::dac8563
