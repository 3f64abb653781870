// Seeded random numbers for the plant: std::mt19937_64 with our own uniform and Gaussian
// transforms, so the same seed gives the same sequence on every standard library.
// Value type (copied by save/restore); every method is real-time safe.
#pragma once

#include <cstdint>
#include <random>

namespace selfsense::plant {

class Random final {
 public:
  explicit Random(std::uint64_t seed) : engine_{seed} {}
  // Uniform on (0, 1).
  double uniform() noexcept { return (static_cast<double>(engine_() >> 11U) + 0.5) * 0x1.0p-53; }
  // Standard normal (Box-Muller, the second value kept for the next call).
  double gaussian() noexcept;

 private:
  std::mt19937_64 engine_;
  double spare_{0.0};
  bool has_spare_{false};
};

}  // namespace selfsense::plant
