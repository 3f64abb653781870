// Regressor streams: the batch form of the operators for identification, one row per sample.
//
// Operator columns, per sample: q_i = p_i - p_{i+1} (p_{n+1} = 0) for the PI partial sums W_i,
// so that H[x] = sum_i W_i q_i, then the creep lags z_rj for c_rj. Dead-zone columns use the
// slope basis of a superposition, S(v) = sum_j G_j B_j(v):
//   B_0 = v - Zu_1(v) - Zl_1(v),  B+_j = Zu_j - Zu_{j+1},  B-_j = Zl_j - Zl_{j+1}
// (Zu_j = max(v - d+_j, 0), Zl_j = min(v - d-_j, 0), Z_{m+1} = 0), whose coefficients G are the
// slopes of S on its intervals: S increasing <=> every G > 0, a simple bound.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "selfsense/operators/dead_zone_superposition.hpp"

namespace selfsense::identification {

struct OperatorBasis {
  std::vector<double> thresholds{};  // r_0 = 0 first; creep thresholds are a subset
  std::vector<std::size_t> creep_rows{};
  std::vector<double> eigenvalues{};
  std::vector<double> gains{};  // a_j = 1 - exp(-lambda_j Ts)

  [[nodiscard]] std::size_t plays() const noexcept { return thresholds.size(); }
  [[nodiscard]] std::size_t creep() const noexcept {
    return creep_rows.size() * eigenvalues.size();
  }
  [[nodiscard]] std::size_t columns() const noexcept { return plays() + creep(); }
};

// Operator columns of successive samples, from the state after `history` with settled creep.
class RegressorStream {
 public:
  RegressorStream(const OperatorBasis& basis, std::span<const double> history);
  // Advances with input x; the returned view is valid until the next call. Real-time safe.
  std::span<const double> next(double x) noexcept;

  // State: the plays, then the creep lags. Saving and restoring copy, never allocate.
  [[nodiscard]] std::size_t state_size() const noexcept { return plays_.size() + lags_.size(); }
  void save_state(std::span<double> out) const noexcept;
  void restore_state(std::span<const double> in) noexcept;

 private:
  const OperatorBasis* basis_;
  std::vector<double> plays_{};
  std::vector<double> lags_{};
  std::vector<double> row_{};
};

// Dead-zone thresholds of a superposition (positive side increasing, negative decreasing).
struct DeadZoneBasis {
  std::vector<double> upper{};
  std::vector<double> lower{};

  [[nodiscard]] std::size_t columns() const noexcept { return 1 + upper.size() + lower.size(); }
  // B_0, B+_1.., B-_1.. at v into out (size columns()).
  void evaluate(double v, std::span<double> out) const noexcept;
  // The superposition with slopes G (size columns(); G_0 is the slope around 0).
  [[nodiscard]] operators::DeadZoneSuperposition::Params superposition(
      std::span<const double> slopes) const;
};

// Thresholds spread evenly over the positive and the negative part of v's range (a side is
// left out when v hardly reaches it).
[[nodiscard]] DeadZoneBasis spread_dead_zones(std::span<const double> v, std::size_t per_side);

}  // namespace selfsense::identification
