// Prandtl-Ishlinskii (PI) hysteresis operator and its closed-form inverse.
//
//   H[x][k] = w_0 * x[k] + sum_{i=1..n} w_i * p_i[k],   p_i = play with threshold r_i,
//   0 < r_1 < ... < r_n.
//
// Internally the linear term is the play with r_0 = 0 (p_0 = x), so the state is the vector
// (p_0, p_1, ..., p_n) of n + 1 play outputs: p_0 is the last input, p_i the remanent
// memory. Invertible iff every partial sum W_i = w_0 + ... + w_i > 0 (checked on
// construction). The inverse is again a PI operator (Kuhnen 2003):
//   r'_i = sum_{j<=i} w_j (r_i - r_j),   w'_0 = 1 / w_0,   w'_i = -w_i / (W_i W_{i-1}),
// with initial play states p'_i = W_i p_i + sum_{j>i} w_j p_j, so that H^-1[H[x]] = x from
// the current state on. Units: the output has the unit of w_0 * x.
//
// step() is real-time safe: O(n), no allocation, no exceptions.
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace selfsense::operators {

class PrandtlIshlinskii final {
 public:
  struct Params {
    double linear_weight{1.0};         // w_0 > 0
    std::vector<double> thresholds{};  // r_1..r_n, strictly increasing, > 0
    std::vector<double> weights{};     // w_1..w_n, partial sums with w_0 stay > 0

    [[nodiscard]] bool is_valid(std::string* why) const;
  };

  // Throws ParameterError naming the offending parameter. All plays start at 0.
  explicit PrandtlIshlinskii(const Params& params);

  [[nodiscard]] Params params() const;
  [[nodiscard]] std::size_t size() const noexcept { return thresholds_.size(); }

  double step(double x) noexcept;
  // Batch form: y[k] = step(x[k]); x and y may alias.
  void apply(std::span<const double> x, std::span<double> y) noexcept;
  // Output for the current state (the last value step() returned).
  [[nodiscard]] double output() const noexcept;

  // State (p_0..p_n). set_state copies size() values; it does not check admissibility
  // (|p_i - p_{i+1}| <= r_{i+1} - r_i), which any real input history satisfies.
  [[nodiscard]] std::span<const double> state() const noexcept { return plays_; }
  void set_state(std::span<const double> plays) noexcept;
  // Demagnetised state at input x: every play at x.
  void reset(double x = 0.0) noexcept;

  // The inverse operator, its state set so that it continues from this operator's state.
  [[nodiscard]] PrandtlIshlinskii inverse() const;

  // Closed-form inverse on the internal representation (index 0 is the linear term):
  // fills r_inv, w_inv (size n + 1) from r, w. Real-time safe.
  static void inverse_parameters(std::span<const double> r, std::span<const double> w,
                                 std::span<double> r_inv, std::span<double> w_inv) noexcept;
  // Inverse play states p'_i = W_i p_i + sum_{j>i} w_j p_j. Real-time safe.
  static void inverse_state(std::span<const double> w, std::span<const double> plays,
                            std::span<double> inverse_plays) noexcept;

 private:
  PrandtlIshlinskii() = default;

  std::vector<double> thresholds_{};  // r_0 = 0, r_1..r_n
  std::vector<double> weights_{};     // w_0..w_n
  std::vector<double> plays_{};       // p_0..p_n
};

}  // namespace selfsense::operators
