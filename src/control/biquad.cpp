#include "selfsense/control/biquad.hpp"

#include <cassert>
#include <cmath>
#include <numbers>

#include "selfsense/base/format_number.hpp"
#include "selfsense/control/parameter_error.hpp"

namespace selfsense::control {

bool BiquadCoefficients::is_valid(std::string* why) const {
  if (!check::finite("Biquad.b0", b0, why) || !check::finite("Biquad.b1", b1, why) ||
      !check::finite("Biquad.b2", b2, why) || !check::finite("Biquad.a1", a1, why) ||
      !check::finite("Biquad.a2", a2, why)) {
    return false;
  }
  if (!(std::abs(a2) < 1.0)) {
    return check::fail("Biquad.a2",
                       base::format_number(a2) + " must be inside (-1, 1) (unstable poles)", why);
  }
  if (!(std::abs(a1) < 1.0 + a2)) {
    // Appended piece by piece: GCC 12 warns (-Wrestrict) on "literal" + std::string here.
    std::string message = "|";
    message += base::format_number(a1);
    message += "| must be < 1 + a2 = ";
    message += base::format_number(1.0 + a2);
    message += " (unstable poles)";
    return check::fail("Biquad.a1", message, why);
  }
  return true;
}

bool BiquadCoefficients::is_stable() const noexcept {
  return std::isfinite(b0) && std::isfinite(b1) && std::isfinite(b2) && std::abs(a2) < 1.0 &&
         std::abs(a1) < 1.0 + a2;
}

double BiquadCoefficients::dc_gain() const noexcept {
  return (b0 + b1 + b2) / (1.0 + a1 + a2);
}

std::complex<double> BiquadCoefficients::response(double frequency,
                                                  double sample_time) const noexcept {
  const std::complex<double> z1 =
      std::polar(1.0, -2.0 * std::numbers::pi * frequency * sample_time);
  const std::complex<double> z2 = z1 * z1;
  return (b0 + b1 * z1 + b2 * z2) / (1.0 + a1 * z1 + a2 * z2);
}

Biquad::Biquad(const BiquadCoefficients& coefficients) : c_(coefficients) {
  std::string why;
  require_valid(c_.is_valid(&why), why);
}

bool Biquad::set_coefficients(const BiquadCoefficients& coefficients) noexcept {
  if (!coefficients.is_stable()) return false;
  c_ = coefficients;
  return true;
}

void Biquad::reset(double x) noexcept {
  const double y = c_.dc_gain() * x;
  s2_ = c_.b2 * x - c_.a2 * y;
  s1_ = y - c_.b0 * x;
}

void Biquad::save_state(std::span<double> out) const noexcept {
  assert(out.size() >= kStateSize);
  out[0] = s1_;
  out[1] = s2_;
}

void Biquad::restore_state(std::span<const double> in) noexcept {
  assert(in.size() >= kStateSize);
  s1_ = in[0];
  s2_ = in[1];
}

}  // namespace selfsense::control
