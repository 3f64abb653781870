// Inner loops shared by the operators: banks of plays, first-order lags and dead zones.
//
// Plain functions on spans so that every operator runs the same vectorisable loop and the
// identification code can reuse them on whole signals. All are real-time safe: no
// allocation, no exceptions. Sizes are the caller's contract (asserted in debug builds).
#pragma once

#include <algorithm>
#include <cassert>
#include <cstddef>
#include <span>

namespace selfsense::operators::kernels {

// Plays p_i[k] = max(x - r_i, min(x + r_i, p_i[k-1])) for every threshold r_i.
inline void play_bank_step(double x, std::span<const double> thresholds,
                           std::span<double> outputs) noexcept {
  assert(thresholds.size() == outputs.size());
  const std::size_t n = thresholds.size();
  const double* r = thresholds.data();
  double* p = outputs.data();
  for (std::size_t i = 0; i < n; ++i)
    p[i] = std::min(std::max(p[i], x - r[i]), x + r[i]);
}

// sum_i w_i * v_i.
inline double dot(std::span<const double> weights, std::span<const double> values) noexcept {
  assert(weights.size() == values.size());
  double sum = 0.0;
  for (std::size_t i = 0; i < weights.size(); ++i)
    sum += weights[i] * values[i];
  return sum;
}

// First-order lags z_j[k] = z_j[k-1] + a_j * (x - z_j[k-1]), a_j = 1 - exp(-lambda_j * Ts),
// returning sum_j c_j * z_j[k].
inline double lag_bank_step(double x, std::span<const double> gains,
                            std::span<const double> weights, std::span<double> states) noexcept {
  assert(gains.size() == states.size() && weights.size() == states.size());
  double sum = 0.0;
  for (std::size_t j = 0; j < states.size(); ++j) {
    states[j] += gains[j] * (x - states[j]);
    sum += weights[j] * states[j];
  }
  return sum;
}

// One-sided dead zones (Kuhnen): sum_i s_i * max(y - d_i, 0) over thresholds d_i > 0 ...
inline double upper_dead_zone_sum(double y, std::span<const double> thresholds,
                                  std::span<const double> weights) noexcept {
  assert(thresholds.size() == weights.size());
  double sum = 0.0;
  for (std::size_t i = 0; i < thresholds.size(); ++i) {
    sum += weights[i] * std::max(y - thresholds[i], 0.0);
  }
  return sum;
}

// ... and sum_i s_i * min(y - d_i, 0) over thresholds d_i < 0.
inline double lower_dead_zone_sum(double y, std::span<const double> thresholds,
                                  std::span<const double> weights) noexcept {
  assert(thresholds.size() == weights.size());
  double sum = 0.0;
  for (std::size_t i = 0; i < thresholds.size(); ++i) {
    sum += weights[i] * std::min(y - thresholds[i], 0.0);
  }
  return sum;
}

}  // namespace selfsense::operators::kernels
