#include "selfsense/identification/regressors.hpp"

#include <algorithm>
#include <cassert>

#include "selfsense/operators/kernels.hpp"

namespace selfsense::identification {

void DeadZoneBasis::evaluate(double v, std::span<double> out) const noexcept {
  assert(out.size() == columns());
  const auto side = [v](const std::vector<double>& d, bool up, std::span<double> cols) {
    double first = 0.0;
    for (std::size_t j = 0; j < d.size(); ++j) {
      const double zj = up ? std::max(v - d[j], 0.0) : std::min(v - d[j], 0.0);
      const double zn =
          j + 1 < d.size() ? (up ? std::max(v - d[j + 1], 0.0) : std::min(v - d[j + 1], 0.0)) : 0.0;
      if (j == 0) first = zj;
      cols[j] = zj - zn;
    }
    return first;
  };
  const double zu1 = side(upper, true, out.subspan(1, upper.size()));
  const double zl1 = side(lower, false, out.subspan(1 + upper.size(), lower.size()));
  out[0] = v - zu1 - zl1;
}

operators::DeadZoneSuperposition::Params DeadZoneBasis::superposition(
    std::span<const double> slopes) const {
  assert(slopes.size() == columns());
  operators::DeadZoneSuperposition::Params p;
  p.linear_weight = slopes[0];
  double previous = slopes[0];
  for (std::size_t j = 0; j < upper.size(); ++j) {
    p.upper_thresholds.push_back(upper[j]);
    p.upper_weights.push_back(slopes[1 + j] - previous);
    previous = slopes[1 + j];
  }
  previous = slopes[0];
  for (std::size_t j = 0; j < lower.size(); ++j) {
    p.lower_thresholds.push_back(lower[j]);
    p.lower_weights.push_back(slopes[1 + upper.size() + j] - previous);
    previous = slopes[1 + upper.size() + j];
  }
  return p;
}

DeadZoneBasis spread_dead_zones(std::span<const double> v, std::size_t per_side) {
  DeadZoneBasis out;
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  const double span = *hi - *lo;
  for (std::size_t j = 1; j <= per_side; ++j) {
    const double f = static_cast<double>(j) / static_cast<double>(per_side + 1);
    if (*hi > 0.05 * span) out.upper.push_back(f * *hi);
    if (*lo < -0.05 * span) out.lower.push_back(f * *lo);
  }
  return out;
}

}  // namespace selfsense::identification
