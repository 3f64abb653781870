// Nonlinear creep operators (paper section 3.4).
//
// ThresholdCreep: a weighted sum of elementary creep elements, each a play with threshold
// r_i followed by a first-order lag with eigenvalue lambda_j, so creep depends on the input's
// history like hysteresis does:
//   K[x] = sum_{i,j} c_ij * z_ij,   dz_ij/dt = lambda_j * (P_{r_i}[x] - z_ij),   c_ij >= 0
// discretised exactly as in LinearCreep. r_0 = 0 is allowed (the element is then a linear
// lag of x). The output is linear in the weights c_ij, which keeps identification convex.
//
// NonlinearCreep: the paper's eq. (28), K[x] = L[H[x]], a linear creep operator behind a PI
// operator. Because L is linear, L[H[x]] = sum_{i,j} (c_j w_i) z_ij: a ThresholdCreep whose
// weight matrix has rank one (as_threshold_creep()).
//
// step() is real-time safe for both: O(n_r * n_lambda), no allocation, no exceptions.
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "selfsense/operators/linear_creep.hpp"
#include "selfsense/operators/prandtl_ishlinskii.hpp"

namespace selfsense::operators {

class ThresholdCreep final {
 public:
  struct Params {
    std::vector<double> thresholds{};   // r_i >= 0, strictly increasing
    std::vector<double> eigenvalues{};  // lambda_j > 0 [1/s]
    std::vector<double> weights{};      // c_ij >= 0, row-major: weights[i * n_lambda + j]

    [[nodiscard]] bool is_valid(std::string* why) const;
  };

  // Throws ParameterError naming the offending parameter. Plays and lags start at 0.
  ThresholdCreep(Params params, double sample_time);

  [[nodiscard]] const Params& params() const noexcept { return params_; }
  [[nodiscard]] double sample_time() const noexcept { return sample_time_; }

  double step(double x) noexcept;
  void apply(std::span<const double> x, std::span<double> y) noexcept;
  [[nodiscard]] double output() const noexcept;

  // State: the plays (n_r values) followed by the lags (row-major, n_r * n_lambda values).
  [[nodiscard]] std::span<const double> state() const noexcept { return state_; }
  void set_state(std::span<const double> state) noexcept;
  // Equilibrium at a constant input x.
  void reset(double x = 0.0) noexcept;

 private:
  Params params_{};
  double sample_time_{0.0};
  std::vector<double> gains_{};  // a_j, repeated for every row: gains_[i * n_lambda + j]
  std::vector<double> state_{};  // plays, then lags

  [[nodiscard]] std::span<double> plays() noexcept {
    return std::span(state_).first(params_.thresholds.size());
  }
  [[nodiscard]] std::span<double> lags() noexcept {
    return std::span(state_).subspan(params_.thresholds.size());
  }
};

// Creep elements equal to L[H[x]]: thresholds {0, r_1..r_n}, weights c_ij = w_i c_j. Throws
// ParameterError if either parameter set is invalid or a PI weight is negative (creep weights
// must stay non-negative).
[[nodiscard]] ThresholdCreep::Params rank_one_creep(const PrandtlIshlinskii::Params& hysteresis,
                                                    const LinearCreep::Params& creep);

class NonlinearCreep final {
 public:
  // Throws ParameterError if the creep parameters or sample time are invalid.
  NonlinearCreep(PrandtlIshlinskii hysteresis, LinearCreep creep)
      : hysteresis_(std::move(hysteresis)), creep_(std::move(creep)) {}

  double step(double x) noexcept { return creep_.step(hysteresis_.step(x)); }
  void apply(std::span<const double> x, std::span<double> y) noexcept;

  [[nodiscard]] const PrandtlIshlinskii& hysteresis() const noexcept { return hysteresis_; }
  [[nodiscard]] const LinearCreep& creep() const noexcept { return creep_; }

  // The same operator as creep elements (rank_one_creep); throws ParameterError if a PI
  // weight is negative.
  [[nodiscard]] ThresholdCreep::Params as_threshold_creep() const;

 private:
  PrandtlIshlinskii hysteresis_;
  LinearCreep creep_;
};

}  // namespace selfsense::operators
