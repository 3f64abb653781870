// Deterministic test signals.
#pragma once

#include <cstddef>
#include <cstdint>
#include <random>
#include <vector>

namespace selfsense::test {

// A bounded random walk in [lo, hi] with Gaussian increments of standard deviation `step`,
// reflected at the bounds; fixed seed so every run sees the same signal.
inline std::vector<double> random_walk(std::size_t n, double lo, double hi, double step,
                                       std::uint64_t seed = 42) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> increment(0.0, step);
  std::vector<double> x(n);
  double v = 0.5 * (lo + hi);
  for (double& out : x) {
    v += increment(rng);
    if (v > hi) v = 2.0 * hi - v;
    if (v < lo) v = 2.0 * lo - v;
    out = v;
  }
  return x;
}

// Piecewise linear signal through the given turning points, `per_segment` samples per segment
// (the first point itself is the first sample).
inline std::vector<double> through(const std::vector<double>& points, std::size_t per_segment) {
  std::vector<double> x{points.front()};
  for (std::size_t i = 1; i < points.size(); ++i) {
    for (std::size_t k = 1; k <= per_segment; ++k) {
      const double s = static_cast<double>(k) / static_cast<double>(per_segment);
      x.push_back(points[i - 1] + s * (points[i] - points[i - 1]));
    }
  }
  return x;
}

}  // namespace selfsense::test
