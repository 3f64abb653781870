// A cascade of up to kMaxSections biquads, fixed storage: the loop's "two notches + a low-pass".
//
//   y = H_{n-1}( ... H_1( H_0(x) ) ... ),   H(z) = prod_i H_i(z)
//
// Sections run in the order given. An empty chain passes its input through.
//
// Real-time safe: step(), reset(), set_section(), assign(), save_state(), restore_state(). The
// constructor validates and throws ParameterError.
#pragma once

#include <array>
#include <complex>
#include <cstddef>
#include <span>

#include "selfsense/control/biquad.hpp"

namespace selfsense::control {

class FilterChain final {
 public:
  static constexpr std::size_t kMaxSections = 4;

  FilterChain() = default;
  // Throws ParameterError when there are more than kMaxSections or a section is unstable
  // ("FilterChain.sections[1]: Biquad.a2: ...").
  explicit FilterChain(std::span<const BiquadCoefficients> sections);

  [[nodiscard]] std::size_t size() const noexcept { return size_; }
  [[nodiscard]] const BiquadCoefficients& section(std::size_t i) const noexcept;
  // Replaces section i (< size()) while running, keeping its state. False, and nothing changed,
  // when i is out of range or the coefficients are unstable.
  bool set_section(std::size_t i, const BiquadCoefficients& coefficients) noexcept;
  // New sections while running (a reload): a section whose coefficients stay keeps its state;
  // one that changes or is added starts settled at `input` scaled by the DC gain of the sections
  // before it (what it sees at rest: the old state does not fit new coefficients), so a chain
  // of unity-gain filters on a constant input does not bump. False, and nothing changed, when
  // there are more than kMaxSections or a section is unstable.
  bool assign(std::span<const BiquadCoefficients> sections, double input) noexcept;

  double step(double x) noexcept {
    for (std::size_t i = 0; i < size_; ++i)
      x = sections_[i].step(x);
    return x;
  }

  // Steady state for a constant input x: each section settled at its own input.
  void reset(double x = 0.0) noexcept;
  [[nodiscard]] double dc_gain() const noexcept;
  // Product of the sections' responses at frequency f [Hz].
  [[nodiscard]] std::complex<double> response(double frequency, double sample_time) const noexcept;

  [[nodiscard]] std::size_t state_size() const noexcept { return size_ * Biquad::kStateSize; }
  void save_state(std::span<double> out) const noexcept;
  void restore_state(std::span<const double> in) noexcept;

 private:
  std::array<Biquad, kMaxSections> sections_{};
  std::size_t size_{0};
};

}  // namespace selfsense::control
