#include "selfsense/diagnosis/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace selfsense::diagnosis {

double noise_floor(std::span<const double> residual) {
  const std::size_t n = residual.size();
  if (n < 8) return 0.0;
  std::vector<double> d2(n - 2);
  for (std::size_t k = 1; k + 1 < n; ++k)
    d2[k - 1] = residual[k + 1] - 2.0 * residual[k] + residual[k - 1];
  const auto median = [](std::vector<double>& v) {
    const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return *mid;
  };
  const double centre = median(d2);
  for (double& v : d2)
    v = std::abs(v - centre);
  return 1.4826 * median(d2) / std::sqrt(6.0);
}

GainTest paired_gain_test(std::span<const double> before, std::span<const double> after) {
  GainTest out;
  std::vector<double> gains;
  for (std::size_t i = 0; i < before.size() && i < after.size(); ++i) {
    if (!(before[i] > 0.0)) continue;
    const double g = before[i] - after[i];
    if (!std::isfinite(g)) return out;  // a fit that is not finite somewhere gains nothing
    gains.push_back(g);
  }
  const std::size_t n = gains.size();
  out.blocks = n;
  if (n == 0) return out;
  // Ranks of |g| (1 = smallest); ties are improbable for real-valued gains and get ranks in
  // order.
  std::vector<std::size_t> order(n);
  for (std::size_t i = 0; i < n; ++i)
    order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return std::abs(gains[a]) < std::abs(gains[b]); });
  std::size_t w_minus = 0;
  for (std::size_t r = 0; r < n; ++r) {
    if (!(gains[order[r]] > 0.0)) w_minus += r + 1;
  }
  // ways[w]: sign patterns of ranks 1..n whose negative ranks sum to w.
  const std::size_t total = n * (n + 1) / 2;
  std::vector<double> ways(total + 1, 0.0);
  ways[0] = 1.0;
  for (std::size_t r = 1; r <= n; ++r) {
    for (std::size_t w = total; w >= r; --w)
      ways[w] += ways[w - r];
  }
  double at_most = 0.0;
  for (std::size_t w = 0; w <= w_minus; ++w)
    at_most += ways[w];
  out.w_minus = static_cast<double>(w_minus);
  out.p_value = at_most / std::pow(2.0, static_cast<double>(n));
  out.significant = out.p_value <= 1.0 - kConfidence;
  return out;
}

}  // namespace selfsense::diagnosis
