// Operator memory carried from a running model to its replacement at a hot swap (private to
// selfsense::models). Every play whose threshold the running model also has takes that play's
// output; every creep lag whose (threshold, eigenvalue) pair it also has takes that lag's
// output. The rest starts from the current input: a play at the last input x (the state it
// would have after resting there), a lag settled at its play. Real-time safe: lookups over a
// few dozen thresholds, no allocation.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <span>

namespace selfsense::models::detail {

// A read-only view of one operator's memory. Creep lags are row-major: one row per creep
// threshold, one column per eigenvalue.
struct OperatorMemory {
  std::span<const double> thresholds{};
  std::span<const double> plays{};
  std::span<const double> creep_thresholds{};
  std::span<const double> eigenvalues{};
  std::span<const double> lags{};
};

// At most the two sides of a model, both driven by the same input.
struct ModelMemory {
  std::array<OperatorMemory, 2> operators{};
  std::size_t count{0};
  double last_input{0.0};

  void add(const OperatorMemory& m) noexcept {
    if (count < operators.size()) operators[count++] = m;
  }
};

[[nodiscard]] inline bool same_value(double a, double b) noexcept {
  return std::abs(a - b) <= 1e-9 * std::max(std::abs(a), std::abs(b));
}

// The running model's play at threshold r, or the last input if it has none.
[[nodiscard]] inline double carried_play(const ModelMemory& from, double r) noexcept {
  for (std::size_t o = 0; o < from.count; ++o) {
    const OperatorMemory& m = from.operators[o];
    for (std::size_t i = 0; i < m.thresholds.size() && i < m.plays.size(); ++i) {
      if (same_value(m.thresholds[i], r)) return m.plays[i];
    }
  }
  return from.last_input;
}

// The running model's lag (r, lambda), or `settled` if it has none.
[[nodiscard]] inline double carried_lag(const ModelMemory& from, double r, double lambda,
                                        double settled) noexcept {
  for (std::size_t o = 0; o < from.count; ++o) {
    const OperatorMemory& m = from.operators[o];
    const std::size_t n_eig = m.eigenvalues.size();
    for (std::size_t i = 0; i < m.creep_thresholds.size(); ++i) {
      if (!same_value(m.creep_thresholds[i], r)) continue;
      for (std::size_t j = 0; j < n_eig; ++j) {
        if (same_value(m.eigenvalues[j], lambda) && i * n_eig + j < m.lags.size()) {
          return m.lags[i * n_eig + j];
        }
      }
    }
  }
  return settled;
}

// Fills `state` (plays, then lags, the layout of OperatorMemory) for an operator with these
// thresholds from the running model's memory.
inline void carry_over(const ModelMemory& from, std::span<const double> thresholds,
                       std::span<const double> creep_thresholds,
                       std::span<const double> eigenvalues, std::span<double> state) noexcept {
  const std::size_t n = thresholds.size();
  for (std::size_t i = 0; i < n; ++i)
    state[i] = carried_play(from, thresholds[i]);
  const std::size_t n_eig = eigenvalues.size();
  for (std::size_t i = 0; i < creep_thresholds.size(); ++i) {
    double settled = from.last_input;
    for (std::size_t k = 0; k < n; ++k) {
      if (same_value(thresholds[k], creep_thresholds[i])) settled = state[k];
    }
    for (std::size_t j = 0; j < n_eig; ++j) {
      state[n + i * n_eig + j] = carried_lag(from, creep_thresholds[i], eigenvalues[j], settled);
    }
  }
}

}  // namespace selfsense::models::detail
