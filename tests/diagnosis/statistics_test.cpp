// The diagnosis's decision statistics (statistics.hpp): the noise floor from the second
// difference of a residual, and the signed-rank test of held-out gains.
#include "selfsense/diagnosis/statistics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace selfsense::diagnosis {
namespace {

TEST(NoiseFloor, FindsWhiteNoiseUnderASlowModelError) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 1e-3);
  std::vector<double> e(20000);
  for (std::size_t k = 0; k < e.size(); ++k) {
    // A model error 50x the noise, slow against the sample rate, and a few steps.
    const double slow = 0.05 * std::sin(2.0 * std::numbers::pi * static_cast<double>(k) / 4000.0);
    const double steps = (k / 2500) % 2 == 0 ? 0.0 : 0.02;
    e[k] = slow + steps + noise(rng);
  }
  EXPECT_NEAR(noise_floor(e), 1e-3, 0.05e-3);
  EXPECT_EQ(noise_floor(std::vector<double>(5, 1.0)), 0.0);
}

TEST(SignedRankTest, ExactProbabilitiesOfTenBlocks) {
  std::vector<double> before(10, 1.0);
  std::vector<double> after(10);
  // Gains 0.01 .. 0.10: every block gains, p = 1 / 2^10.
  for (std::size_t i = 0; i < 10; ++i)
    after[i] = 1.0 - 0.01 * static_cast<double>(i + 1);
  GainTest t = paired_gain_test(before, after);
  EXPECT_EQ(t.blocks, 10U);
  EXPECT_DOUBLE_EQ(t.p_value, 1.0 / 1024.0);
  EXPECT_TRUE(t.significant);
  // Ranks 2 and 3 lose (W- = 5): 10 of 1024 patterns sum to <= 5, the 99 % critical value.
  after[1] = 1.02;
  after[2] = 1.03;
  t = paired_gain_test(before, after);
  EXPECT_DOUBLE_EQ(t.w_minus, 5.0);
  EXPECT_DOUBLE_EQ(t.p_value, 10.0 / 1024.0);
  EXPECT_TRUE(t.significant);
  // W- = 6 (ranks 2 and 4): 14 of 1024, not significant.
  after[2] = 0.97;
  after[3] = 1.04;
  t = paired_gain_test(before, after);
  EXPECT_DOUBLE_EQ(t.w_minus, 6.0);
  EXPECT_DOUBLE_EQ(t.p_value, 14.0 / 1024.0);
  EXPECT_FALSE(t.significant);
}

TEST(SignedRankTest, AGainInAFewBlocksCountsWhenTheOthersDoNotLose) {
  // A delay helps much at the fast moves and a little elsewhere.
  const std::vector<double> before{5.0, 1.0, 1.0, 9.0, 1.0, 1.0, 1.0, 7.0, 1.0, 1.0};
  const std::vector<double> after{1.0, 0.99, 0.98, 1.0, 0.99, 0.995, 0.99, 1.0, 0.98, 0.99};
  EXPECT_TRUE(paired_gain_test(before, after).significant);
}

TEST(SignedRankTest, RandomSignsAreNotSignificant) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g(0.0, 0.01);
  int significant = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    std::vector<double> before(10, 1.0);
    std::vector<double> after(10);
    for (double& a : after)
      a = 1.0 + g(rng);
    if (paired_gain_test(before, after).significant) ++significant;
  }
  // The test's size: at most 1 % (exactly 10/1024 for ten blocks), within sampling error.
  EXPECT_LE(significant, 20);
}

}  // namespace
}  // namespace selfsense::diagnosis
