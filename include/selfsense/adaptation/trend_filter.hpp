// A slow figure and its slope from irregular measurements (one per drive cycle, one per hold),
// for the health estimates (health_estimator.hpp). Two first-order filters of the same input
// with time constants tau1 < tau2, stepped at the measurement times t_k [s]:
//   a_i[k]  = 1 - exp(-(t_k - t_{k-1}) / tau_i)
//   y_i[k]  = y_i[k-1] + a_i[k] (x[k] - y_i[k-1])            y_i[0] = x[0]
//   value   = y_1                                            [unit of x]
//   slope   = (y_1 - y_2) / (tau2 - tau1)                    [unit of x per s]
// On a ramp x = x0 + r t each filter settles to lag r tau_i behind it, so the slope is r exactly
// once both have settled (about 3 tau2), and the value lags the ramp by r tau1.
// Real-time safe: update() is noexcept and allocation-free.
#pragma once

#include <cstddef>
#include <span>

namespace selfsense::adaptation {

class TrendFilter final {
 public:
  TrendFilter() = default;
  // tau1 < tau2, both > 0 (checked by the caller's configuration).
  TrendFilter(double tau1_s, double tau2_s) noexcept : tau1_{tau1_s}, tau2_{tau2_s} {}

  void update(double x, double t_s) noexcept;
  [[nodiscard]] bool has_value() const noexcept { return count_ > 0; }
  [[nodiscard]] double value() const noexcept { return y1_; }
  [[nodiscard]] double slope() const noexcept;  // per s; 0 before the second measurement
  [[nodiscard]] double last() const noexcept { return last_; }
  [[nodiscard]] double count() const noexcept { return count_; }
  void clear() noexcept;

  static constexpr std::size_t kStateSize{5};  // y1, y2, t, count, last
  void save_state(std::span<double> out) const noexcept;
  void restore_state(std::span<const double> in) noexcept;

 private:
  double tau1_{1.0};
  double tau2_{2.0};
  double y1_{0.0};
  double y2_{0.0};
  double t_{0.0};
  double count_{0.0};
  double last_{0.0};
};

}  // namespace selfsense::adaptation
