#include "selfsense/runtime/cycle_stats.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>

#include "selfsense/runtime/latency_histogram.hpp"

namespace selfsense::runtime {
namespace {

TEST(LatencyHistogram, BucketsArePowersOfTwo) {
  EXPECT_EQ(LatencyHistogram::bucket_of(-5), 0U);
  EXPECT_EQ(LatencyHistogram::bucket_of(0), 0U);
  EXPECT_EQ(LatencyHistogram::bucket_of(1), 1U);
  EXPECT_EQ(LatencyHistogram::bucket_of(2), 2U);
  EXPECT_EQ(LatencyHistogram::bucket_of(3), 2U);
  EXPECT_EQ(LatencyHistogram::bucket_of(4), 3U);
  EXPECT_EQ(LatencyHistogram::bucket_of(1023), 10U);
  EXPECT_EQ(LatencyHistogram::bucket_of(1024), 11U);
  EXPECT_EQ(LatencyHistogram::bucket_of(std::numeric_limits<std::int64_t>::max()), 63U);
  EXPECT_EQ(LatencyHistogram::bucket_upper_ns(0), 0);
  EXPECT_EQ(LatencyHistogram::bucket_upper_ns(11), 2047);
  EXPECT_EQ(LatencyHistogram::bucket_upper_ns(63), std::numeric_limits<std::int64_t>::max());
}

TEST(LatencyHistogram, EmptyReadsZero) {
  const LatencyHistogram h;
  EXPECT_EQ(h.count(), 0);
  EXPECT_EQ(h.percentile_ns(0.99), 0);
  EXPECT_EQ(h.mean_ns(), 0.0);
}

TEST(LatencyHistogram, PercentilesAreTheTopOfTheirBucketCappedAtTheMax) {
  LatencyHistogram h;
  for (int k = 0; k < 900; ++k)
    h.record(1000);  // [512, 1023]
  for (int k = 0; k < 99; ++k)
    h.record(3000);  // [2048, 4095]
  h.record(-7);      // counts as 0
  EXPECT_EQ(h.count(), 1000);
  EXPECT_EQ(h.sum_ns(), 900 * 1000 + 99 * 3000);
  EXPECT_EQ(h.bucket_count(0), 1);
  EXPECT_EQ(h.bucket_count(10), 900);
  EXPECT_EQ(h.bucket_count(12), 99);
  EXPECT_EQ(h.percentile_ns(0.001), 0);  // rank 1: the zero
  EXPECT_EQ(h.percentile_ns(0.5), 1023);
  EXPECT_EQ(h.percentile_ns(0.901), 1023);  // rank 901: the last 1000 (the zero is rank 1)
  EXPECT_EQ(h.percentile_ns(0.902), 3000);  // rank 902: bucket top 4095, capped at the max
  EXPECT_EQ(h.percentile_ns(1.0), 3000);
  EXPECT_EQ(h.max_ns(), 3000);
  EXPECT_DOUBLE_EQ(h.mean_ns(), 1197.0);
  h.reset();
  EXPECT_EQ(h.count(), 0);
  EXPECT_EQ(h.bucket_count(10), 0);
}

TEST(CycleStats, CountsCyclesOverBudgetAndReadsPercentiles) {
  CycleStats stats(40'000);  // 40 us of a 50 us period
  for (int k = 0; k < 10'000; ++k)
    stats.record(k % 1000 == 999 ? 45'000 : 12'000);
  EXPECT_EQ(stats.count(), 10'000);
  EXPECT_EQ(stats.over_budget(), 10);
  EXPECT_EQ(stats.max_ns(), 45'000);
  EXPECT_EQ(stats.last_ns(), 45'000);
  EXPECT_EQ(stats.percentile_ns(0.5), 16'383);    // 12 us in [8192, 16383]
  EXPECT_EQ(stats.percentile_ns(0.999), 16'383);  // rank 9990 of 9990 at 12 us
  EXPECT_EQ(stats.percentile_ns(0.9991), 45'000);
  EXPECT_EQ(stats.sum_ns(), 9990LL * 12'000 + 10LL * 45'000);
  EXPECT_DOUBLE_EQ(stats.mean_ns(), 12'033.0);
  stats.reset();
  EXPECT_EQ(stats.count(), 0);
  EXPECT_EQ(stats.over_budget(), 0);
}

TEST(CycleStats, NoBudgetCountsNothingOver) {
  CycleStats stats;
  stats.record(1'000'000'000);
  EXPECT_EQ(stats.over_budget(), 0);
  EXPECT_EQ(stats.count(), 1);
}

}  // namespace
}  // namespace selfsense::runtime
