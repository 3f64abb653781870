// Setpoint shaping: a slew-rate limit followed by an optional smoothing filter, so that a
// stepped or jumping setpoint (socket, staircase) reaches the loop without exciting the
// actuator's resonance. Sample time Ts [s] fixed at construction.
//
// Units: the setpoint's [x] (strain, Pa); slew_rate R [x/s]; time_constant tau [s].
//
// Difference equations, target r[k]:
//   q[k] = q[k-1] + clamp(r[k] - q[k-1], -R Ts, R Ts)     slew limit (R = 0: q[k] = r[k])
//   none:          y[k] = q[k]
//   first order:   p[k] = p[k-1] + a (q[k] - p[k-1]),  y[k] = p[k],   a = 1 - exp(-Ts / tau)
//   second order:  p as above, y[k] = y[k-1] + a (p[k] - y[k-1])
// Each lag is the exact discretisation of 1 / (tau s + 1) for an input held over the sample.
// The second order is two equal lags: a double pole at exp(-Ts / tau), critically damped
// (1 / (tau s + 1)^2), so steps settle without overshoot. The filters have unit DC gain and
// non-negative impulse responses, so the shaped setpoint never moves faster than R either.
//
// reset(value) starts every state at value (the measured state at arm: no jump).
//
// Real-time safe: step(), reset(), save_state(), restore_state(). The constructor validates and
// throws ParameterError naming the parameter.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace selfsense::control {

class SetpointShaper final {
 public:
  enum class Filter : std::uint8_t { kNone, kFirstOrder, kSecondOrder };

  struct Params {
    double slew_rate{0.0};  // R [x/s] >= 0; 0 = no slew limit
    Filter filter{Filter::kNone};
    double time_constant{0.0};  // tau [s] > 0 when filter != kNone

    [[nodiscard]] bool is_valid(double sample_time, std::string* why) const;
    friend bool operator==(const Params&, const Params&) = default;
  };

  static constexpr std::size_t kStateSize = 3;

  // Throws ParameterError naming the parameter. Starts at 0; call reset(value) before use.
  SetpointShaper(const Params& params, double sample_time);

  [[nodiscard]] const Params& params() const noexcept { return params_; }

  // Shaped setpoint for target r[k].
  double step(double target) noexcept;
  [[nodiscard]] double output() const noexcept { return output_; }

  void reset(double value) noexcept;

  [[nodiscard]] static constexpr std::size_t state_size() noexcept { return kStateSize; }
  void save_state(std::span<double> out) const noexcept;
  void restore_state(std::span<const double> in) noexcept;

 private:
  Params params_{};
  double max_step_{0.0};  // R Ts; 0 = unlimited
  double lag_gain_{1.0};  // a
  double slewed_{0.0};    // q
  double lagged_{0.0};    // p
  double output_{0.0};    // y
};

}  // namespace selfsense::control
