// The batch form of the PI and creep operators: one regressor row per sample, for
// identification (the columns a fit weighs) and for models that are linear in their weights
// (the stress-dependent model evaluates W . q every sample).
//
// Operator columns, per sample: q_i = p_i - p_{i+1} (p_{n+1} = 0) for the PI partial sums W_i,
// so that H[x] = sum_i W_i q_i, then the creep lags z_rj for c_rj, discretised exactly:
//   z[k] = z[k-1] + a_j (p_r[k] - z[k-1]),   a_j = 1 - exp(-lambda_j Ts),
// then the hinges max(0, p_r[k] - b_h) for c_h (play_hinges.hpp).
// RegressorStream::next() and the state copies are real-time safe (no allocation, no throw).
#pragma once

#include <cstddef>
#include <span>
#include <vector>

namespace selfsense::operators {

struct OperatorBasis {
  std::vector<double> thresholds{};  // r_0 = 0 first; creep thresholds are a subset
  std::vector<std::size_t> creep_rows{};
  std::vector<double> eigenvalues{};
  std::vector<double> gains{};            // a_j = 1 - exp(-lambda_j Ts)
  std::vector<std::size_t> hinge_rows{};  // play index of each hinge
  std::vector<double> hinge_levels{};     // b_h

  [[nodiscard]] std::size_t plays() const noexcept { return thresholds.size(); }
  [[nodiscard]] std::size_t creep() const noexcept {
    return creep_rows.size() * eigenvalues.size();
  }
  [[nodiscard]] std::size_t hinges() const noexcept { return hinge_rows.size(); }
  [[nodiscard]] std::size_t columns() const noexcept { return plays() + creep() + hinges(); }
};

// Operator columns of successive samples, from the state after `history` with settled creep.
class RegressorStream {
 public:
  RegressorStream(const OperatorBasis& basis, std::span<const double> history);
  // Advances with input x; the returned view is valid until the next call. Real-time safe.
  std::span<const double> next(double x) noexcept;
  // Advances through the inputs xs to the state next() on each would leave, bit for bit,
  // without forming their rows (a fit that reads every m-th row). Real-time safe.
  void skip(std::span<const double> xs) noexcept;

  [[nodiscard]] const OperatorBasis& basis() const noexcept { return *basis_; }
  [[nodiscard]] std::span<const double> plays() const noexcept { return plays_; }
  [[nodiscard]] std::span<const double> lags() const noexcept { return lags_; }

  // State: the plays, then the creep lags. Saving and restoring copy, never allocate.
  [[nodiscard]] std::size_t state_size() const noexcept { return plays_.size() + lags_.size(); }
  void save_state(std::span<double> out) const noexcept;
  void restore_state(std::span<const double> in) noexcept;

 private:
  void step_lags() noexcept;

  const OperatorBasis* basis_;
  std::vector<double> plays_{};
  std::vector<double> spare_{};  // the plays' next state, swapped in
  std::vector<double> lags_{};
  std::vector<double> row_{};
};

}  // namespace selfsense::operators
