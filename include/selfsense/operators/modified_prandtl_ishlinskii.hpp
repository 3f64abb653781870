// Modified Prandtl-Ishlinskii operator (Kuhnen): a PI operator followed by a dead-zone
// superposition, Gamma[x] = S[H[x]]. Covers asymmetric and saturating loops and keeps a
// closed-form inverse Gamma^-1[y] = H^-1[S^-1[y]].
//
// step() is real-time safe: O(n + m), no allocation, no exceptions.
#pragma once

#include <span>
#include <utility>

#include "selfsense/operators/dead_zone_superposition.hpp"
#include "selfsense/operators/prandtl_ishlinskii.hpp"

namespace selfsense::operators {

class ModifiedPrandtlIshlinskiiInverse;

class ModifiedPrandtlIshlinskii final {
 public:
  ModifiedPrandtlIshlinskii(PrandtlIshlinskii hysteresis, DeadZoneSuperposition superposition)
      : hysteresis_(std::move(hysteresis)), superposition_(std::move(superposition)) {}

  [[nodiscard]] const PrandtlIshlinskii& hysteresis() const noexcept { return hysteresis_; }
  [[nodiscard]] PrandtlIshlinskii& hysteresis() noexcept { return hysteresis_; }
  [[nodiscard]] const DeadZoneSuperposition& superposition() const noexcept {
    return superposition_;
  }

  double step(double x) noexcept { return superposition_.evaluate(hysteresis_.step(x)); }
  void apply(std::span<const double> x, std::span<double> y) noexcept;

  // Inverse continuing from the current state.
  [[nodiscard]] ModifiedPrandtlIshlinskiiInverse inverse() const;

 private:
  PrandtlIshlinskii hysteresis_;
  DeadZoneSuperposition superposition_;
};

// x = H^-1[S^-1[y]]: desired output in, input out.
class ModifiedPrandtlIshlinskiiInverse final {
 public:
  ModifiedPrandtlIshlinskiiInverse(PrandtlIshlinskii inverse_hysteresis,
                                   DeadZoneSuperposition inverse_superposition)
      : inverse_hysteresis_(std::move(inverse_hysteresis)),
        inverse_superposition_(std::move(inverse_superposition)) {}

  double step(double y) noexcept {
    return inverse_hysteresis_.step(inverse_superposition_.evaluate(y));
  }
  void apply(std::span<const double> y, std::span<double> x) noexcept;

 private:
  PrandtlIshlinskii inverse_hysteresis_;
  DeadZoneSuperposition inverse_superposition_;
};

}  // namespace selfsense::operators
