// Collocated vibration damping on a self-sensed signal.
//
// The paper's smart-actuator applications damp a cantilever beam with the actuator's own
// sensor signal: Dosch et al. with the linear reconstruction (section 3.1, eqs. 7-8), and the
// bending transducer of section 3.2 with the stored eps(E) characteristic, which brought the
// beam to rest 60x faster (20x with a constant eps). Here the measured signal y is the
// reconstructed S_hat (or T_hat) of the same actuator that applies u: sensor and actuator are
// collocated, which is what makes both laws below robustly stable on a lightly damped mode.
//
// Units: y [x] (strain or Pa), u [u] (field, V/m); fc, f_f [Hz].
//
// Positive position feedback (PPF, Goh and Caughey): a second-order low-pass tuned to the
// resonance, fed back with positive sign,
//   u = g * wf^2 / (s^2 + 2 zeta_f wf s + wf^2) * y,       g [u/x] > 0, wf = 2 pi f_f
// Near wf the filter adds 90 deg of lag, so u acts like viscous damping on the mode; above it
// rolls off (no spill-over into higher modes). Stable while g * G(0) < 1 for a plant of
// static gain G(0) [x/u]; zeta_f of 0.3-0.5 is usual.
//
// Velocity feedback: a band-limited derivative with negative sign,
//   u = -g * s / (tau s + 1) * y,     g [u s/x] > 0,   tau = 1 / (2 pi fc)
//
// PPF passes DC with gain g: on a signal with a static part (the self-sensed strain of a biased
// actuator) set dc_block_frequency f_b > 0, which puts a first-order high-pass
// s / (s + 2 pi f_b) in front of either law. Keep f_b well below the resonance (a tenth or
// less): its phase lead at f_f detunes the PPF filter.
//
// Each filter is discretised by the bilinear transform and runs as a biquad in direct form II
// transposed (see biquad.hpp). PPF and the high-pass are pre-warped at f_f and f_b, so they are
// exact there; the velocity filter is not (K = 2 / Ts), so its derivative gain is exact at low
// frequency (a ramp of slope v gives u = -g v) and its corner lands at (2 / Ts) atan(pi fc Ts)
// [rad/s]. Per sample, with H_b the high-pass (identity when f_b = 0) and H the law's filter:
//   y_b[k] = H_b(y)[k],   w[k] = H(y_b)[k]
//   u[k]   = clamp(sign * g * w[k], -u_limit, u_limit),   sign = +1 (PPF) or -1 (velocity)
//
// Real-time safe: step(), reset(), save_state(), restore_state(). The constructor validates and
// throws ParameterError naming the parameter.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string>

#include "selfsense/control/biquad.hpp"

namespace selfsense::control {

class DampingController final {
 public:
  enum class Law : std::uint8_t { kPositivePosition, kVelocity };

  struct Params {
    Law law{Law::kPositivePosition};
    double gain{0.0};       // g > 0: [u/x] for PPF, [u s/x] for velocity feedback
    double frequency{0.0};  // PPF: f_f [Hz], tuned to the resonance; velocity: corner fc [Hz]
    double damping{0.5};    // PPF: zeta_f > 0
    double output_limit{std::numeric_limits<double>::infinity()};  // u_limit [u] > 0
    double dc_block_frequency{0.0};  // f_b [Hz] >= 0; 0 = no high-pass in front

    [[nodiscard]] bool is_valid(double sample_time, std::string* why) const;
    friend bool operator==(const Params&, const Params&) = default;
  };

  static constexpr std::size_t kStateSize = 2 * Biquad::kStateSize;

  // Throws ParameterError naming the parameter ("DampingController.frequency: ...").
  DampingController(const Params& params, double sample_time);

  [[nodiscard]] const Params& params() const noexcept { return params_; }
  // The filter without gain and sign.
  [[nodiscard]] const BiquadCoefficients& filter() const noexcept { return filter_.coefficients(); }

  double step(double measurement) noexcept {
    return std::clamp(signed_gain_ * filter_.step(dc_block_.step(measurement)),
                      -params_.output_limit, params_.output_limit);
  }
  // Steady state for a constant measurement y (no transient at arm).
  void reset(double measurement = 0.0) noexcept;

  [[nodiscard]] static constexpr std::size_t state_size() noexcept { return kStateSize; }
  void save_state(std::span<double> out) const noexcept;
  void restore_state(std::span<const double> in) noexcept;

 private:
  Params params_{};
  Biquad dc_block_{};  // pass-through when dc_block_frequency is 0
  Biquad filter_{};
  double signed_gain_{0.0};
};

}  // namespace selfsense::control
