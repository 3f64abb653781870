#include "selfsense/diagnosis/read_later.hpp"

#include <array>
#include <cmath>
#include <cstddef>

#include "selfsense/models/cubic_read.hpp"

namespace selfsense::diagnosis {

std::vector<double> read_later(std::span<const double> x, double samples) {
  std::vector<double> out(x.begin(), x.end());
  if (!(samples > 0.0) || !std::isfinite(samples) || x.empty()) return out;
  const std::size_t n = x.size();
  for (std::size_t k = 0; k < n; ++k) {
    const double p = static_cast<double>(k) + samples;
    const double whole = std::floor(p);
    if (whole >= static_cast<double>(n - 1)) {
      out[k] = x[n - 1];
      continue;
    }
    const auto i = static_cast<std::size_t>(whole);
    const double t = p - whole;
    if (i == 0 || i + 2 >= n) {
      out[k] = x[i] + t * (x[i + 1] - x[i]);
      continue;
    }
    const std::array<double, 4> w = models::cubic_read_weights(t);
    out[k] = w[0] * x[i - 1] + w[1] * x[i] + w[2] * x[i + 1] + w[3] * x[i + 2];
  }
  return out;
}

}  // namespace selfsense::diagnosis
