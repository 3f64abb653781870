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
#include "selfsense/operators/regressor_stream.hpp"

namespace selfsense::identification {

// OperatorBasis and RegressorStream live with the operators (operators/regressor_stream.hpp).
using operators::OperatorBasis;
using operators::RegressorStream;

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
