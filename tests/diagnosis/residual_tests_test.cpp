// Residual analysis: correlation bounds, located segments and the holds of a drive.
#include "selfsense/diagnosis/residual_tests.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace selfsense::diagnosis {
namespace {

std::vector<double> white(std::size_t n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<double> x(n);
  for (double& v : x)
    v = normal(rng);
  return x;
}

TEST(CorrelationTest, WhiteResidualStaysWithinItsBoundAndAFilteredOneDoesNot) {
  const std::vector<double> e = white(20000, 1);
  const std::vector<double> u = white(20000, 2);
  const CorrelationTest t = correlation_test(e, u);
  EXPECT_NEAR(t.bound, 2.576 / std::sqrt(20000.0), 1e-12);
  EXPECT_LE(t.auto_outside, 0.1);
  EXPECT_LE(t.cross_outside, 0.1);
  // A residual that follows the input one sample late: whiteness holds, independence does not.
  std::vector<double> late(e.size());
  for (std::size_t k = 1; k < e.size(); ++k)
    late[k] = u[k - 1] + 0.1 * e[k];
  const CorrelationTest l = correlation_test(late, u);
  EXPECT_GT(l.cross_correlation[static_cast<std::size_t>(l.max_lag) + 1], 0.9);
  EXPECT_GT(l.cross_outside, 0.0);
}

TEST(LargeSegments, FindsTheBurstInANoisyResidual) {
  std::vector<double> e = white(10000, 3);
  for (std::size_t k = 6000; k < 6300; ++k)
    e[k] *= 10.0;
  const std::vector<Segment> s = large_segments(e, 3.0, 3);
  ASSERT_EQ(s.size(), 1U);
  EXPECT_LE(s[0].begin, 6000U + 100U);
  EXPECT_GE(s[0].end, 6300U - 100U);
}

// Steps with short ramps between holds of 1000 samples, then a sine (no holds).
TEST(HoldsOf, EachHoldWithTheRampLeadingIntoIt) {
  std::vector<double> x;
  double level = 0.0;
  for (const double next : {1.0, 0.2, 0.21, 2.0}) {
    for (int k = 1; k <= 20; ++k)  // a ramp of 20 samples
      x.push_back(level + (next - level) * k / 20.0);
    x.insert(x.end(), 1000, next);
    level = next;
  }
  const std::size_t steps_end = x.size();
  for (int k = 0; k < 4000; ++k)
    x.push_back(1.0 + std::sin(0.05 * k));
  const std::vector<Segment> h = holds_of(x);
  // 0.2 -> 0.21 stays within 5 % of the range: one hold. A hold ends where the drive leaves
  // the band about the level it stepped to (a few samples into the next ramp).
  ASSERT_EQ(h.size(), 3U);
  EXPECT_EQ(h[0].begin, 0U);
  EXPECT_NEAR(static_cast<double>(h[0].end), 1020.0, 5.0);
  EXPECT_EQ(h[1].begin, h[0].end);
  EXPECT_NEAR(static_cast<double>(h[1].end), 3060.0, 5.0);
  EXPECT_EQ(h[2].begin, h[1].end);  // the ramp into the last level belongs to it
  EXPECT_EQ(h[2].end, steps_end);
  EXPECT_TRUE(holds_of(std::vector<double>(500, 1.0)).size() == 1U);
  EXPECT_TRUE(holds_of({}).empty());
}

}  // namespace
}  // namespace selfsense::diagnosis
