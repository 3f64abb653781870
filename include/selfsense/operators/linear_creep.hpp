// Linear creep operator: a weighted bank of first-order lags (paper section 3.4).
//
//   dz_j/dt = lambda_j * (x - z_j),   L[x] = sum_j c_j * z_j,   lambda_j > 0 [1/s], c_j >= 0
//
// Exact discretisation with sample time Ts, the input held at x[k] over (t_{k-1}, t_k]:
//   z_j[k] = z_j[k-1] + a_j * (x[k] - z_j[k-1]),   a_j = 1 - exp(-lambda_j * Ts).
// A unit step applied just after t_{-1} therefore gives L[k] = sum_j c_j (1 - exp(-lambda_j
// (k + 1) Ts)), the analytic response sampled exactly (step_response()). Non-negative weights
// keep the creep monotone after a step and the inverse of (1 + L) stable (its zeros interlace
// the poles on the negative real axis).
//
// Eigenvalues are usually spaced logarithmically, one per decade from the sample rate down
// to minutes (log_spaced_eigenvalues()).
//
// step() is real-time safe: O(n), no allocation, no exceptions.
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace selfsense::operators {

class LinearCreep final {
 public:
  struct Params {
    std::vector<double> eigenvalues{};  // lambda_j > 0 [1/s]
    std::vector<double> weights{};      // c_j >= 0

    [[nodiscard]] bool is_valid(std::string* why) const;
  };

  // Throws ParameterError naming the offending parameter (or the sample time). States at 0.
  LinearCreep(Params params, double sample_time);

  [[nodiscard]] const Params& params() const noexcept { return params_; }
  [[nodiscard]] double sample_time() const noexcept { return sample_time_; }
  [[nodiscard]] std::size_t size() const noexcept { return states_.size(); }
  // sum_j c_j: the static gain of L (output per unit input after every lag settled).
  [[nodiscard]] double static_gain() const noexcept;
  // sum_j c_j a_j: the part of this sample's input that reaches this sample's output.
  [[nodiscard]] double instant_gain() const noexcept;

  double step(double x) noexcept;
  void apply(std::span<const double> x, std::span<double> y) noexcept;
  [[nodiscard]] double output() const noexcept;

  [[nodiscard]] std::span<const double> state() const noexcept { return states_; }
  void set_state(std::span<const double> states) noexcept;
  // Equilibrium at a constant input x: every lag settled at x.
  void reset(double x = 0.0) noexcept;

  // Analytic response to a unit step at t = 0: sum_j c_j (1 - exp(-lambda_j t)).
  [[nodiscard]] static double step_response(const Params& params, double t) noexcept;

 private:
  Params params_{};
  double sample_time_{0.0};
  std::vector<double> gains_{};  // a_j
  std::vector<double> states_{};
};

// n eigenvalues from `fastest` down to `slowest` [1/s], equally spaced in log. Throws
// ParameterError unless fastest > slowest > 0 and n >= 2 (n == 1 gives {fastest}).
[[nodiscard]] std::vector<double> log_spaced_eigenvalues(double fastest, double slowest,
                                                         std::size_t n);

}  // namespace selfsense::operators
