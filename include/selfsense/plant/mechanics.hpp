// Stack plus load as a mass-spring-damper driven towards its static equilibrium x_eq:
//   x'' + 2 zeta w x' + w^2 x = w^2 x_eq,   x_eq = (k_s L S_free + F_ext) / (k_s + k_load)
// Exact discretisation for x_eq linear between samples (first-order hold), computed once from
// the augmented matrix exponential:
//   [x; v][k] = Phi [x; v][k-1] + G0 x_eq[k-1] + G1 (x_eq[k] - x_eq[k-1])
// Unconditionally stable at any sample rate. A zero-order hold would delay the drive by half a
// sample and feed energy into the undamped resonator; the ramp keeps the D-E loop dissipative.
// peek() and update() are real-time safe.
#pragma once

namespace selfsense::plant {

class Mechanics final {
 public:
  Mechanics() = default;
  Mechanics(double resonance_hz, double damping_ratio, double sample_time_s);
  void reset(double x_eq) noexcept {
    x_ = x_eq;
    v_ = 0.0;
    x_eq_prev_ = x_eq;
  }
  // The position x (m) one sample on, with x_eq ramping from its previous value; peek() leaves
  // the state alone, update() advances it (both give the same x).
  [[nodiscard]] double peek(double x_eq) const noexcept;
  double update(double x_eq) noexcept;
  [[nodiscard]] double position() const noexcept { return x_; }
  [[nodiscard]] double velocity() const noexcept { return v_; }

 private:
  double phi_[2][2]{};
  double g0_[2]{};
  double g1_[2]{};
  double x_{0.0};
  double x_eq_prev_{0.0};
  double v_{0.0};
};

}  // namespace selfsense::plant
