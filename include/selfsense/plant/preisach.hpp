// Scalar Preisach hysteresis: a continuum of relays r(alpha, beta) (up at input >= alpha, down
// at input <= beta, else unchanged), weighted by a density mu(alpha, beta) on the triangle
// field_min <= beta <= alpha <= field_max (HysteresisConfig in config.hpp).
//
// Evaluated exactly through the Everett function F(a, b) = integral of mu over
// {b <= beta <= alpha <= a} and the memory of alternating dominant extrema
// m0 < ... (m0 = field_min), M1 > M2 > ..., m1 < m2 < ... with the wiping-out property:
//   S+ = sum_k [F(M_k, m_{k-1}) - F(M_k, m_k)],  p = 2 S+ / F(max, min) - 1  in [-1, 1],
// the current input closing the sequence. F is tabulated on a (levels x levels) grid and
// interpolated bilinearly, so the output is continuous in the input and rate independent.
// The memory holds at most kCapacity turning points; beyond that the innermost loop is merged.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "selfsense/plant/config.hpp"

namespace selfsense::plant {

// Everett table: constant after construction, shared by every state.
class EverettTable final {
 public:
  explicit EverettTable(const HysteresisConfig& config);
  // F(a, b) for field_min <= b <= a <= field_max (arguments are clamped); normalised so that
  // F(field_max, field_min) = 1. Real-time safe.
  [[nodiscard]] double operator()(double a, double b) const noexcept;
  [[nodiscard]] double field_min() const noexcept { return lo_; }
  [[nodiscard]] double field_max() const noexcept { return hi_; }

 private:
  [[nodiscard]] double node(std::size_t i, std::size_t j) const noexcept {
    return table_[i * n_ + j];
  }
  std::size_t n_{};
  double lo_{};
  double hi_{};
  double step_{};
  std::vector<double> table_{};  // n_ x n_, F(x_i, x_j), zero for j >= i
};

// The memory (turning points) of one Preisach operator: a value type, copied by save/restore.
class PreisachState final {
 public:
  static constexpr std::size_t kCapacity{96};

  // Starts with every relay down and then raises the input from field_min to `input`.
  void reset(const EverettTable& table, double input) noexcept;
  // Applies the input and returns p in [-1, 1]. Real-time safe, O(1) amortised.
  double update(const EverettTable& table, double input) noexcept;
  [[nodiscard]] double output() const noexcept { return output_; }
  [[nodiscard]] std::size_t turning_points() const noexcept { return size_; }

 private:
  void recompute_last(const EverettTable& table) noexcept;
  std::array<double, kCapacity> points_{};   // m0, M1, m1, M2, ... , current input
  std::array<double, kCapacity> partial_{};  // partial_[i]: S+ contributed by points 1..i
  std::size_t size_{0};
  double output_{0.0};
};

}  // namespace selfsense::plant
