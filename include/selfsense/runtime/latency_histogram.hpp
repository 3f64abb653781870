// Durations [ns] in power-of-two buckets, for the loop's tail latencies without storing samples:
//   bucket 0 holds 0, bucket b >= 1 holds [2^(b-1), 2^b - 1]  (64 buckets cover every int64)
// A percentile is read as the top of the bucket that holds it, capped at the largest value
// recorded: an upper bound at most a factor 2 above the true value, exact for the maximum.
// Everything is real-time safe: fixed storage, no allocation, no exceptions, no locks. Not
// thread-safe: one writer, readers on the same thread (copy it out through a lock-free box).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace selfsense::runtime {

class LatencyHistogram final {
 public:
  static constexpr std::size_t kBuckets = 64;

  // Negative durations count as 0.
  void record(std::int64_t ns) noexcept;
  void reset() noexcept { *this = LatencyHistogram{}; }

  [[nodiscard]] std::int64_t count() const noexcept { return count_; }
  [[nodiscard]] std::int64_t sum_ns() const noexcept { return sum_ns_; }
  [[nodiscard]] std::int64_t max_ns() const noexcept { return max_ns_; }
  // 0 when empty.
  [[nodiscard]] double mean_ns() const noexcept;
  // Upper bound of the q-quantile, 0 < q <= 1 (0.5, 0.99, 0.999; 1 gives max_ns()); 0 when
  // empty.
  [[nodiscard]] std::int64_t percentile_ns(double q) const noexcept;

  [[nodiscard]] std::int64_t bucket_count(std::size_t b) const noexcept { return buckets_[b]; }
  [[nodiscard]] static std::size_t bucket_of(std::int64_t ns) noexcept;
  // Largest duration bucket b holds.
  [[nodiscard]] static std::int64_t bucket_upper_ns(std::size_t b) noexcept;

 private:
  std::array<std::int64_t, kBuckets> buckets_{};
  std::int64_t count_{0};
  std::int64_t sum_ns_{0};
  std::int64_t max_ns_{0};
};

}  // namespace selfsense::runtime
