#include "selfsense/operators/typical_stack.hpp"

#include <cmath>

#include "selfsense/operators/linear_creep.hpp"

namespace selfsense::operators {
namespace {

// Hysteresis-creep parameters with output `full_scale` at kTypicalFieldMax, loop width set by
// `hysteresis_share` and creep per decade `creep_per_decade` (both relative to full scale).
HysteresisCreep::Params scaled_stack(const TypicalStackSize& size, double full_scale,
                                     double hysteresis_share, double creep_per_decade) {
  const double e_max = kTypicalFieldMax;
  PrandtlIshlinskii::Params h;
  const auto n = static_cast<double>(size.plays);
  double play_weight_sum = 0.0;
  for (std::size_t i = 1; i <= size.plays; ++i) {
    const double r = e_max * 0.5 * static_cast<double>(i) / (n + 1.0);
    const double w = std::exp(-3.0 * r / e_max);
    h.thresholds.push_back(r);
    h.weights.push_back(w);
    play_weight_sum += w;
  }
  // Play weights carry the hysteresis share of the gain, the linear term the rest.
  const double gain = full_scale / e_max;
  const double play_scale = size.plays > 0 ? hysteresis_share * 4.0 * gain / play_weight_sum : 0;
  for (double& w : h.weights)
    w *= play_scale;
  h.linear_weight = gain * (1.0 - 2.0 * hysteresis_share);

  DeadZoneSuperposition::Params s;
  for (std::size_t i = 1; i <= size.dead_zones; ++i) {
    s.upper_thresholds.push_back(full_scale * (0.6 + 0.1 * static_cast<double>(i)));
    s.upper_weights.push_back(-0.05);
  }

  ThresholdCreep::Params c;
  c.eigenvalues = log_spaced_eigenvalues(100.0, 0.01, size.eigenvalues);
  for (std::size_t i = 0; i <= size.creep_plays && (i == 0 || i <= size.plays); ++i) {
    c.thresholds.push_back(i == 0 ? 0.0 : h.thresholds[i - 1]);
  }
  // After a step dE each lag adds c_j dE within about a decade of its time constant, so
  // c_j = creep_per_decade * gain / (lags per decade), shared among the creep thresholds.
  const double lags_per_decade =
      size.eigenvalues > 1 ? static_cast<double>(size.eigenvalues - 1) / 4.0 : 1.0;
  c.weights.assign(
      c.thresholds.size() * c.eigenvalues.size(),
      creep_per_decade * gain / lags_per_decade / static_cast<double>(c.thresholds.size()));
  return HysteresisCreep::Params{h, s, c};
}

}  // namespace

HysteresisCreep::Params typical_stack_strain(const TypicalStackSize& size) {
  return scaled_stack(size, 1.5e-3, 0.12, 0.015);
}

HysteresisCreep::Params typical_stack_charge(const TypicalStackSize& size) {
  return scaled_stack(size, 0.1, 0.15, 0.01);
}

}  // namespace selfsense::operators
