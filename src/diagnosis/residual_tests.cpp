#include "selfsense/diagnosis/residual_tests.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace selfsense::diagnosis {
namespace {

std::vector<double> centred(std::span<const double> x) {
  const double mean =
      x.empty() ? 0.0 : std::accumulate(x.begin(), x.end(), 0.0) / static_cast<double>(x.size());
  std::vector<double> out(x.size());
  for (std::size_t k = 0; k < x.size(); ++k)
    out[k] = x[k] - mean;
  return out;
}

double energy(const std::vector<double>& x) {
  return std::inner_product(x.begin(), x.end(), x.begin(), 0.0);
}

}  // namespace

CorrelationTest correlation_test(std::span<const double> residual, std::span<const double> input,
                                 int max_lag) {
  CorrelationTest t;
  t.max_lag = max_lag;
  const std::size_t n = residual.size();
  if (max_lag < 1 || n < 2 * static_cast<std::size_t>(max_lag) + 2) return t;
  const std::vector<double> e = centred(residual);
  const std::vector<double> u = centred(input.size() == n ? input : residual);
  const double ee = energy(e);
  const double uu = energy(u);
  t.bound = 2.576 / std::sqrt(static_cast<double>(n));
  const auto lagged = [n](const std::vector<double>& a, const std::vector<double>& b, int lag) {
    double sum = 0.0;  // sum_k a[k + lag] b[k]
    const std::size_t shift = static_cast<std::size_t>(std::abs(lag));
    for (std::size_t k = 0; k + shift < n; ++k) {
      sum += lag >= 0 ? a[k + shift] * b[k] : a[k] * b[k + shift];
    }
    return sum;
  };
  int outside = 0;
  for (int lag = 0; lag <= max_lag; ++lag) {
    const double r = ee > 0.0 ? lagged(e, e, lag) / ee : 0.0;
    t.autocorrelation.push_back(r);
    if (lag > 0 && std::abs(r) > t.bound) ++outside;
  }
  t.auto_outside = static_cast<double>(outside) / static_cast<double>(max_lag);
  outside = 0;
  for (int lag = -max_lag; lag <= max_lag; ++lag) {
    const double r = (ee > 0.0 && uu > 0.0) ? lagged(e, u, lag) / std::sqrt(ee * uu) : 0.0;
    t.cross_correlation.push_back(r);
    if (std::abs(r) > t.bound) ++outside;
  }
  t.cross_outside = static_cast<double>(outside) / static_cast<double>(2 * max_lag + 1);
  return t;
}

std::vector<Segment> large_segments(std::span<const double> residual, double factor,
                                    std::size_t max_segments) {
  const std::size_t n = residual.size();
  std::vector<Segment> out;
  if (n == 0) return out;
  const std::size_t w = std::max<std::size_t>(16, n / 100);
  double total = 0.0;
  for (const double r : residual)
    total += r * r;
  const double rms = std::sqrt(total / static_cast<double>(n));
  if (!(rms > 0.0)) return out;
  const double limit = factor * factor * rms * rms * static_cast<double>(w);
  // Moving sum of squares over [k - w/2, k + w/2).
  std::vector<double> cum(n + 1, 0.0);
  for (std::size_t k = 0; k < n; ++k)
    cum[k + 1] = cum[k] + residual[k] * residual[k];
  struct Scored {
    Segment s{};
    double energy{0.0};
  };
  std::vector<Scored> found;
  bool inside = false;
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t lo = k >= w / 2 ? k - w / 2 : 0;
    const std::size_t hi = std::min(n, lo + w);
    const bool large =
        (cum[hi] - cum[lo]) * static_cast<double>(w) / static_cast<double>(hi - lo) > limit;
    if (large && !inside) {
      if (!found.empty() && k - found.back().s.end < w) {
        inside = true;  // merge with the previous one
      } else {
        found.push_back({{k, k + 1}, 0.0});
        inside = true;
      }
    }
    if (inside) {
      if (large) {
        found.back().s.end = k + 1;
      } else {
        inside = false;
      }
    }
  }
  for (Scored& f : found)
    f.energy = cum[f.s.end] - cum[f.s.begin];
  std::sort(found.begin(), found.end(),
            [](const Scored& a, const Scored& b) { return a.energy > b.energy; });
  if (found.size() > max_segments) found.resize(max_segments);
  for (const Scored& f : found)
    out.push_back(f.s);
  std::sort(out.begin(), out.end(),
            [](const Segment& a, const Segment& b) { return a.begin < b.begin; });
  return out;
}

std::vector<Segment> holds_of(std::span<const double> drive) {
  const std::size_t n = drive.size();
  if (n == 0) return {};
  const std::size_t shortest = std::max<std::size_t>(16, n / 100);
  const auto [lo, hi] = std::minmax_element(drive.begin(), drive.end());
  const double band = 0.05 * (*hi - *lo);
  std::vector<Segment> out;
  std::size_t previous_end = 0;
  std::size_t begin = 0;  // where the drive last stepped to a new level
  for (std::size_t k = 1; k <= n; ++k) {
    if (k < n && std::abs(drive[k] - drive[begin]) <= band) continue;
    if (k - begin >= shortest) {
      out.push_back({std::max(previous_end, begin - std::min(begin, shortest)), k});
      previous_end = k;
    }
    begin = k;
  }
  return out;
}

}  // namespace selfsense::diagnosis
