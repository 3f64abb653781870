// Kuhnen's superposition operator: a memoryless, piecewise linear characteristic built from
// one-sided dead zones, which makes PI loops asymmetric and saturating.
//
//   S[y] = s_0 * y + sum_{i} s_i^+ * max(y - d_i^+, 0) + sum_{i} s_i^- * min(y - d_i^-, 0)
//   0 < d_1^+ < d_2^+ < ...,   0 > d_1^- > d_2^- > ...
//
// Slope on the i-th upper interval: g_i^+ = s_0 + s_1^+ + ... + s_i^+ (likewise below 0).
// Strictly increasing (hence invertible) iff s_0 > 0 and every such partial sum is > 0. The
// inverse is again a dead-zone superposition: d'_i = S[d_i], s'_0 = 1 / s_0,
// s'_i = 1 / g_i - 1 / g_{i-1}. S[0] = 0. Units: output in the unit of s_0 * y.
//
// evaluate() is real-time safe: O(m), no allocation, no exceptions.
#pragma once

#include <span>
#include <string>
#include <vector>

namespace selfsense::operators {

class DeadZoneSuperposition final {
 public:
  struct Params {
    double linear_weight{1.0};               // s_0 > 0
    std::vector<double> upper_thresholds{};  // d_i^+ > 0, strictly increasing
    std::vector<double> upper_weights{};     // s_i^+
    std::vector<double> lower_thresholds{};  // d_i^- < 0, strictly decreasing
    std::vector<double> lower_weights{};     // s_i^-

    [[nodiscard]] bool is_valid(std::string* why) const;
  };

  // The identity S[y] = y.
  DeadZoneSuperposition() = default;
  // Throws ParameterError naming the offending parameter.
  explicit DeadZoneSuperposition(Params params);

  [[nodiscard]] const Params& params() const noexcept { return params_; }
  [[nodiscard]] std::size_t size() const noexcept {
    return params_.upper_thresholds.size() + params_.lower_thresholds.size();
  }

  [[nodiscard]] double evaluate(double y) const noexcept;
  void apply(std::span<const double> y, std::span<double> out) const noexcept;
  // Local slope dS/dy at y (right derivative).
  [[nodiscard]] double slope(double y) const noexcept;

  [[nodiscard]] DeadZoneSuperposition inverse() const;

 private:
  Params params_{};
};

}  // namespace selfsense::operators
