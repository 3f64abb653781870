#include "selfsense/runtime/latency_histogram.hpp"

#include <algorithm>
#include <bit>
#include <cassert>
#include <cmath>

namespace selfsense::runtime {

std::size_t LatencyHistogram::bucket_of(std::int64_t ns) noexcept {
  if (ns <= 0) return 0;
  return static_cast<std::size_t>(std::bit_width(static_cast<std::uint64_t>(ns)));
}

std::int64_t LatencyHistogram::bucket_upper_ns(std::size_t b) noexcept {
  assert(b < kBuckets);
  if (b == 0) return 0;
  // b <= 63, so 2^b - 1 fits in int64.
  return static_cast<std::int64_t>((std::uint64_t{1} << b) - 1);
}

void LatencyHistogram::record(std::int64_t ns) noexcept {
  ns = std::max<std::int64_t>(ns, 0);
  ++buckets_[bucket_of(ns)];
  ++count_;
  sum_ns_ += ns;
  max_ns_ = std::max(max_ns_, ns);
}

double LatencyHistogram::mean_ns() const noexcept {
  return count_ == 0 ? 0.0 : static_cast<double>(sum_ns_) / static_cast<double>(count_);
}

std::int64_t LatencyHistogram::percentile_ns(double q) const noexcept {
  if (count_ == 0) return 0;
  // The rank of the q-quantile among the sorted samples, 1-based.
  // 0.999 * 1000 is 999.0000000000001 in doubles: round products that are integers up to
  // rounding error to that integer, not to the next.
  const double exact = std::clamp(q, 0.0, 1.0) * static_cast<double>(count_);
  const double nearest = std::round(exact);
  const double wanted =
      std::abs(exact - nearest) <= 1e-9 * std::max(1.0, exact) ? nearest : std::ceil(exact);
  const std::int64_t rank = std::max<std::int64_t>(1, static_cast<std::int64_t>(wanted));
  std::int64_t seen = 0;
  for (std::size_t b = 0; b < kBuckets; ++b) {
    seen += buckets_[b];
    if (seen >= rank) return std::min(bucket_upper_ns(b), max_ns_);
  }
  return max_ns_;
}

}  // namespace selfsense::runtime
