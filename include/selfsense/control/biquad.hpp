// Second-order IIR section in direct form II transposed (double precision).
//
//   H(z) = (b0 + b1 z^-1 + b2 z^-2) / (1 + a1 z^-1 + a2 z^-2)
//
//   y[k]  = b0 x[k] + s1[k-1]
//   s1[k] = b1 x[k] - a1 y[k] + s2[k-1]
//   s2[k] = b2 x[k] - a2 y[k]
//
// Units: y has the units of x times the gain of H. A first-order section has b2 = a2 = 0.
// Transposed form II keeps two states and is the usual choice in double precision: the states
// stay of the size of the signal, so notches close to DC do not lose accuracy the way direct
// form I does in single precision. Coefficients come from filter_design.hpp.
//
// Real-time safe: step(), reset(), set_coefficients(), save_state(), restore_state(). The
// constructor validates (finite coefficients, poles strictly inside the unit circle) and throws
// ParameterError.
#pragma once

#include <complex>
#include <cstddef>
#include <span>
#include <string>

namespace selfsense::control {

struct BiquadCoefficients {
  double b0{1.0};
  double b1{0.0};
  double b2{0.0};
  double a1{0.0};
  double a2{0.0};

  // Finite, and both poles strictly inside the unit circle (|a2| < 1, |a1| < 1 + a2).
  [[nodiscard]] bool is_valid(std::string* why) const;
  // The same test without a message: allocation-free, for reloads on the real-time path.
  [[nodiscard]] bool is_stable() const noexcept;
  // H at DC: (b0 + b1 + b2) / (1 + a1 + a2).
  [[nodiscard]] double dc_gain() const noexcept;
  // H(e^{j 2 pi f Ts}) at frequency f [Hz].
  [[nodiscard]] std::complex<double> response(double frequency, double sample_time) const noexcept;
  friend bool operator==(const BiquadCoefficients&, const BiquadCoefficients&) = default;
};

class Biquad final {
 public:
  static constexpr std::size_t kStateSize = 2;

  // Pass-through (H = 1); lets FilterChain hold a fixed array of sections.
  Biquad() = default;
  // Throws ParameterError naming the offending coefficient.
  explicit Biquad(const BiquadCoefficients& coefficients);

  [[nodiscard]] const BiquadCoefficients& coefficients() const noexcept { return c_; }
  // Swaps coefficients while running (reload of a filter); keeps the state. Returns false and
  // changes nothing when `coefficients` is invalid.
  bool set_coefficients(const BiquadCoefficients& coefficients) noexcept;

  double step(double x) noexcept {
    const double y = c_.b0 * x + s1_;
    s1_ = c_.b1 * x - c_.a1 * y + s2_;
    s2_ = c_.b2 * x - c_.a2 * y;
    return y;
  }

  // Steady state for a constant input x: the next outputs are dc_gain() * x with no transient.
  void reset(double x = 0.0) noexcept;

  [[nodiscard]] static constexpr std::size_t state_size() noexcept { return kStateSize; }
  void save_state(std::span<double> out) const noexcept;
  void restore_state(std::span<const double> in) noexcept;

 private:
  BiquadCoefficients c_{};
  double s1_{0.0};
  double s2_{0.0};
};

}  // namespace selfsense::control
