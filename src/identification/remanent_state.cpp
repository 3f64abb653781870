#include "selfsense/identification/remanent_state.hpp"

#include <algorithm>

namespace selfsense::identification {

std::size_t sweep_length(std::span<const double> x) {
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  const double margin = 0.02 * (*hi - *lo);
  bool low = false;
  bool high = false;
  for (std::size_t k = 0; k < x.size(); ++k) {
    low = low || x[k] <= *lo + margin;
    high = high || x[k] >= *hi - margin;
    if (low && high) return k + 1;
  }
  return x.size();
}

std::vector<std::vector<double>> history_candidates(std::span<const double> x) {
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  const double x0 = x.front();
  std::vector<std::vector<double>> out{{x0}};
  constexpr int kLevels = 8;
  for (int i = 0; i <= kLevels; ++i) {
    const double a = *lo + (*hi - *lo) * i / kLevels;
    if (a < x0) out.push_back({*lo, *hi, a, x0});  // came down to a, now rising to x0
    if (a > x0) out.push_back({*hi, *lo, a, x0});  // went up to a, now falling to x0
  }
  return out;
}

std::vector<double> refine_turning_point(
    std::vector<double> h, double step,
    const std::function<double(const std::vector<double>&)>& residual) {
  const double x0 = h.back();
  double& turn = h[h.size() - 2];
  double a = turn - step;
  double b = turn + step;
  if (turn < x0) b = std::min(b, x0);
  if (turn > x0) a = std::max(a, x0);
  constexpr double kGolden = 0.6180339887498949;
  const auto at = [&](double v) {
    turn = v;
    return residual(h);
  };
  double c = b - kGolden * (b - a);
  double d = a + kGolden * (b - a);
  double fc = at(c);
  double fd = at(d);
  for (int i = 0; i < 8; ++i) {
    if (fc < fd) {
      b = d;
      d = c;
      fd = fc;
      c = b - kGolden * (b - a);
      fc = at(c);
    } else {
      a = c;
      c = d;
      fc = fd;
      d = a + kGolden * (b - a);
      fd = at(d);
    }
  }
  turn = fc < fd ? c : d;
  return h;
}

std::vector<std::vector<double>> outside_candidates(std::span<const double> x) {
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  const double x0 = x.front();
  const double range = *hi - *lo;
  std::vector<std::vector<double>> out;
  for (const double distance : {0.125, 0.25, 0.5, 1.0}) {
    const double below = *lo - range * distance;
    const double above = *hi + range * distance;
    out.push_back({*lo, *hi, below, x0});  // swept the range, came down below it, now rising
    out.push_back({*hi, *lo, above, x0});  // swept the range, went up above it, now falling
  }
  return out;
}

}  // namespace selfsense::identification
