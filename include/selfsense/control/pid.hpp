// Parallel PID on the error, derivative on the measurement, with anti-windup and bumpless
// transfer. Sample time Ts [s] fixed at construction.
//
// Units: setpoint r and measurement y share a unit [x] (strain, Pa); the output u and the
// feedforward u_ff share another [u] (V/m of field). kp [u/x], ki [u/(x s)], kd [u s/x].
//
// Difference equations, sample k (the computer form of Astrom and Hagglund):
//   e[k] = r[k] - y[k]
//   P[k] = kp (b r[k] - y[k])                         setpoint weight b on the P term only
//   D[k] = ad D[k-1] - bd (y[k] - y[k-1])             ad = Tf / (Tf + Ts), bd = kd / (Tf + Ts)
//   v[k] = P[k] + I[k] + D[k] + u_ff[k]               feedforward added before the limits
//   u[k] = clamp(v[k], u_min, u_max)
//   I[k+1] = I[k] + c[k] ki Ts e[k] + (Ts / Tt) (u[k] - v[k])
// with c[k] = 0 when conditional integration is on and the output saturates in the direction
// the error pushes (v > u_max and e > 0, or v < u_min and e < 0), else 1. The back-calculation
// term is dropped when Tt = 0.
//
// Discretisation: the derivative filter Tf dD/dt + D = -kd dy/dt by backward Euler (stable
// and non-oscillating for every Tf >= 0; Tf = 0 is the plain difference kd (y[k-1] - y[k]) /
// Ts; at Nyquist its gain is 2 kd / (2 Tf + Ts)); the integral by forward Euler (I[k] uses the
// errors up to k-1, so the output does not depend on the integrator's own update). The
// derivative acts on -y, not on e: a setpoint step gives no derivative kick.
//
// Tf is given directly or as Tf = Td / N with Td = kd / kp (then kp must be > 0).
//
// track(u_applied) tells the controller the output that was really applied (amplifier limit,
// an override, a mode that held the output): the integrator follows it through the
// back-calculation term, I[k+1] += g_t (u_applied - u[k]), g_t = Ts / Tt, or 1 (integrator set
// so that v would have been u_applied) when Tt = 0.
//
// Real-time safe (noexcept, no allocation): step(), track(), set_gains(), set_output_limits(),
// reset(), reset_bumpless(), save_state(), restore_state(). The constructor validates and throws
// ParameterError naming the parameter.
#pragma once

#include <cstddef>
#include <limits>
#include <span>
#include <string>

namespace selfsense::control {

class Pid final {
 public:
  struct Gains {
    double kp{0.0};  // [u/x] >= 0
    double ki{0.0};  // [u/(x s)] >= 0
    double kd{0.0};  // [u s/x] >= 0
    friend bool operator==(const Gains&, const Gains&) = default;
  };

  struct Params {
    Gains gains{};
    double setpoint_weight{1.0};         // b [-], finite
    double derivative_filter_time{0.0};  // Tf [s] >= 0, used when derivative_filter_n == 0
    double derivative_filter_n{0.0};     // N > 0: Tf = kd / (kp N); 0: use derivative_filter_time
    double output_min{-std::numeric_limits<double>::infinity()};  // [u]
    double output_max{std::numeric_limits<double>::infinity()};   // [u] > output_min
    double tracking_time{0.0};  // Tt [s]: 0 = no back-calculation, else >= sample_time
    bool conditional_integration{true};

    [[nodiscard]] bool is_valid(double sample_time, std::string* why) const;
    friend bool operator==(const Params&, const Params&) = default;
  };

  static constexpr std::size_t kStateSize = 6;

  // Throws ParameterError naming the parameter ("Pid.tracking_time: ..."). State at rest.
  Pid(const Params& params, double sample_time);

  [[nodiscard]] const Params& params() const noexcept { return params_; }
  [[nodiscard]] double sample_time() const noexcept { return ts_; }

  // One sample: returns u[k] and advances the integrator and derivative filter.
  double step(double setpoint, double measurement, double feedforward = 0.0) noexcept;
  // After step(): the output actually applied this sample, when it differs from step()'s.
  void track(double applied_output) noexcept;

  // New gains without an output bump: at unchanged r, y and u_ff the next output equals what the
  // old gains would have given. The integral term is in output units, so a new ki needs nothing;
  // the change of kp (b r - y) (and of ad D when N sets Tf) moves into the integrator. The
  // derivative state keeps its value and decays; new kd acts from the next measurement change.
  // Returns false and changes nothing when a gain is negative or not finite, or
  // derivative_filter_n > 0 and kp = 0 < kd.
  bool set_gains(const Gains& gains) noexcept;
  // New output limits while running (a reload); the next step() clamps to them. False, and
  // nothing changed, unless output_min < output_max (neither NaN).
  bool set_output_limits(double output_min, double output_max) noexcept;

  // At rest: I = D = 0; the next step takes its measurement as the previous one.
  void reset() noexcept;
  // Bumpless start from an output that is already applied: the next step(setpoint,
  // measurement, feedforward) returns current_output (limits permitting).
  void reset_bumpless(double measurement, double current_output, double setpoint,
                      double feedforward = 0.0) noexcept;
  // The same with the setpoint at the measured state (bumpless arm).
  void reset_bumpless(double measurement, double current_output) noexcept {
    reset_bumpless(measurement, current_output, measurement);
  }

  [[nodiscard]] double integral() const noexcept { return integral_; }
  [[nodiscard]] double derivative() const noexcept { return derivative_; }
  [[nodiscard]] double output() const noexcept { return output_; }
  // Gain of the derivative path from y to D at the Nyquist frequency: 2 kd / (2 Tf + Ts).
  [[nodiscard]] double derivative_nyquist_gain() const noexcept;

  [[nodiscard]] static constexpr std::size_t state_size() noexcept { return kStateSize; }
  void save_state(std::span<double> out) const noexcept;
  void restore_state(std::span<const double> in) noexcept;

 private:
  [[nodiscard]] double filter_time(const Gains& gains) const noexcept;
  void update_coefficients() noexcept;

  Params params_{};
  double ts_{0.0};
  double ad_{0.0};          // Tf / (Tf + Ts)
  double bd_{0.0};          // kd / (Tf + Ts)
  double track_gain_{1.0};  // Ts / Tt, or 1 when Tt = 0
  // State.
  double integral_{0.0};
  double derivative_{0.0};
  double last_measurement_{0.0};
  double last_setpoint_{0.0};
  double output_{0.0};
  bool primed_{false};  // a previous measurement exists
};

}  // namespace selfsense::control
