#include "selfsense/identification/fit_quality.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace selfsense::identification {

FitQuality fit_quality(std::span<const double> recorded, std::span<const double> model) {
  if (recorded.empty() || recorded.size() != model.size()) {
    throw std::invalid_argument("fit_quality: recorded and model need the same non-zero length");
  }
  const auto [lo, hi] = std::minmax_element(recorded.begin(), recorded.end());
  const double range = *hi - *lo;
  double sum = 0.0;
  double worst = 0.0;
  for (std::size_t k = 0; k < recorded.size(); ++k) {
    const double e = recorded[k] - model[k];
    sum += e * e;
    worst = std::max(worst, std::abs(e));
  }
  const double rms = std::sqrt(sum / static_cast<double>(recorded.size()));
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (!(range > 0.0)) return {rms > 0.0 ? kInf : 0.0, worst > 0.0 ? kInf : 0.0};
  return {rms / range, worst / range};
}

}  // namespace selfsense::identification
