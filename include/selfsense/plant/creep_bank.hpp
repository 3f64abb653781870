// Bank of first-order relaxation elements following one channel's instantaneous response y:
//   z_j[k] = z_j[k-1] + a_j (y[k] - z_j[k-1]),  a_j = 1 - exp(-Ts / tau_j)   (exact for ZOH y)
//   creep[k] = sum_j w_j (z_j[k] - y0)
// After a step of y by dy the creep grows by sum_j w_j dy (1 - exp(-t / tau_j)) and settles.
// Value type without heap memory; peek() and update() are real-time safe.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "selfsense/plant/config.hpp"

namespace selfsense::plant {

class CreepBank final {
 public:
  CreepBank() = default;
  CreepBank(const std::vector<double>& tau_s, const std::vector<double>& weights,
            double sample_time_s);
  void reset(double y) noexcept;
  // creep[k] for the input y without advancing the state (update() returns the same value).
  [[nodiscard]] double peek(double y) const noexcept;
  double update(double y) noexcept;

 private:
  std::array<double, kMaxCreepElements> a_{};
  std::array<double, kMaxCreepElements> w_{};
  std::array<double, kMaxCreepElements> z_{};
  std::size_t n_{0};
  double y0_{0.0};
};

}  // namespace selfsense::plant
