// Biquad design by the bilinear transform with frequency pre-warping.
//
// Each design starts from an analog prototype H(s) and substitutes
//   s = K (1 - z^-1) / (1 + z^-1),   K = w0 / tan(w0 Ts / 2),   w0 = 2 pi f0,
// so that the digital filter has exactly the analog response at f0 (the notch depth, the
// corner gain) while frequencies in between are warped by w_d = (2 / Ts) atan(w_a Ts / 2).
//
// Prototypes (w0 = 2 pi f0):
//   notch       (s^2 + 2 g zeta w0 s + w0^2) / (s^2 + 2 zeta w0 s + w0^2),  zeta = 1 / (2 Q),
//               g = 10^(-depth_db / 20): |H| = g at f0 (finite depth), 1 at DC and Nyquist;
//               Q = f0 / bandwidth, the bandwidth being the -3 dB width of an infinitely deep notch
//   low-pass    w0^2 / (s^2 + (w0 / Q) s + w0^2),  Q = 1/sqrt(2) is the 2nd-order Butterworth
//   high-pass   s^2  / (s^2 + (w0 / Q) s + w0^2)
//   1st order   w0 / (s + w0) low-pass, s / (s + w0) high-pass   (b2 = a2 = 0)
//
// Every corner or centre frequency must be below 0.45 times the sample rate (the warping grows
// without bound towards Nyquist); violations throw ParameterError naming the parameter:
// "NotchDesign.frequency: 5000 must be < 0.45 * sample rate = 4500". Design is not real-time
// work (it validates and may throw); compute coefficients off the loop, then hand them over with
// Biquad::set_coefficients().
#pragma once

#include <numbers>
#include <string>

#include "selfsense/control/biquad.hpp"

namespace selfsense::control {

// Largest allowed design frequency as a fraction of the sample rate.
inline constexpr double kMaxDesignFraction = 0.45;

// H(s) = (n2 s^2 + n1 s + n0) / (d2 s^2 + d1 s + d0).
struct AnalogBiquad {
  double n2{0.0};
  double n1{0.0};
  double n0{1.0};
  double d2{0.0};
  double d1{0.0};
  double d0{1.0};
};

// The bilinear transform of `analog`, pre-warped at `prewarp_frequency` [Hz] (0: no pre-warp,
// K = 2 / Ts). Throws ParameterError when the result is not a stable biquad.
[[nodiscard]] BiquadCoefficients bilinear(const AnalogBiquad& analog, double sample_time,
                                          double prewarp_frequency);

struct NotchDesign {
  double frequency{0.0};  // f0 [Hz], 0 < f0 < 0.45 / Ts
  double quality{0.0};    // Q > 0; or leave 0 and give the bandwidth
  double bandwidth{0.0};  // [Hz] > 0 when quality is 0: Q = f0 / bandwidth
  double depth_db{40.0};  // attenuation at f0 [dB] >= 0, finite

  [[nodiscard]] bool is_valid(double sample_time, std::string* why) const;
  [[nodiscard]] double q() const noexcept {
    return quality > 0.0 ? quality : frequency / bandwidth;
  }
};

struct SecondOrderDesign {
  double frequency{0.0};                      // corner f0 [Hz], 0 < f0 < 0.45 / Ts
  double quality{1.0 / std::numbers::sqrt2};  // Q > 0; the default is Butterworth

  [[nodiscard]] bool is_valid(double sample_time, std::string* why) const;
};

struct FirstOrderDesign {
  double frequency{0.0};  // corner f0 [Hz], 0 < f0 < 0.45 / Ts

  [[nodiscard]] bool is_valid(double sample_time, std::string* why) const;
};

// Each throws ParameterError naming the parameter (or "sample_time").
[[nodiscard]] BiquadCoefficients notch(const NotchDesign& design, double sample_time);
[[nodiscard]] BiquadCoefficients low_pass(const SecondOrderDesign& design, double sample_time);
[[nodiscard]] BiquadCoefficients high_pass(const SecondOrderDesign& design, double sample_time);
[[nodiscard]] BiquadCoefficients low_pass(const FirstOrderDesign& design, double sample_time);
[[nodiscard]] BiquadCoefficients high_pass(const FirstOrderDesign& design, double sample_time);

}  // namespace selfsense::control
