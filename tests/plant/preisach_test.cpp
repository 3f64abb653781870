#include "selfsense/plant/preisach.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace selfsense::plant {
namespace {

HysteresisConfig config() {
  HysteresisConfig c{};
  c.enabled = true;
  return c;
}

TEST(EverettTable, IsNormalisedAndMonotone) {
  const EverettTable f{config()};
  EXPECT_NEAR(f(3.0e6, -1.0e6), 1.0, 1e-12);
  EXPECT_EQ(f(1.0e6, 1.0e6), 0.0);
  EXPECT_LT(f(1.0e6, 0.0), f(1.5e6, 0.0));
  EXPECT_LT(f(1.0e6, 0.5e6), f(1.0e6, 0.0));
}

TEST(PreisachState, SaturatesAtTheEndsOfTheRange) {
  const EverettTable f{config()};
  PreisachState s{};
  s.reset(f, -1.0e6);
  EXPECT_DOUBLE_EQ(s.output(), -1.0);
  EXPECT_NEAR(s.update(f, 3.0e6), 1.0, 1e-12);
  EXPECT_NEAR(s.update(f, -2.0e6), -1.0, 1e-12);
}

TEST(PreisachState, FallingBranchLiesAboveRisingBranch) {
  const EverettTable f{config()};
  PreisachState s{};
  s.reset(f, 0.0);
  const double rising = s.update(f, 1.0e6);
  s.update(f, 2.0e6);
  const double falling = s.update(f, 1.0e6);
  EXPECT_GT(falling - rising, 0.05);
}

TEST(PreisachState, MinorLoopClosesAndIsWipedOut) {
  const EverettTable f{config()};
  PreisachState s{};
  s.reset(f, 0.0);
  const double at_max = s.update(f, 1.6e6);
  s.update(f, 0.8e6);
  s.update(f, 1.2e6);
  s.update(f, 1.0e6);
  // Return-point memory: back at the dominant maximum the minor loops leave no trace.
  EXPECT_NEAR(s.update(f, 1.6e6), at_max, 1e-12);
  EXPECT_EQ(s.turning_points(), 2U);
}

TEST(PreisachState, IsRateIndependent) {
  const EverettTable f{config()};
  PreisachState coarse{};
  PreisachState fine{};
  coarse.reset(f, 0.0);
  fine.reset(f, 0.0);
  const std::vector<double> corners{1.7e6, 0.4e6, 1.3e6};
  double last = 0.0;
  for (const double c : corners) {
    for (int i = 1; i <= 100; ++i)
      fine.update(f, last + (c - last) * i / 100.0);
    coarse.update(f, c);
    last = c;
    EXPECT_NEAR(fine.output(), coarse.output(), 1e-12);
  }
}

// More nested reversals than the memory holds: the oldest loops survive, the output stays on
// the branches, and saturation wipes the whole memory.
TEST(PreisachState, DeepNestingStaysBoundedAndSaturationWipesIt) {
  const EverettTable f{config()};
  PreisachState s{};
  s.reset(f, 0.0);
  const double first_max = s.update(f, 2.0e6);
  for (int i = 1; i < 1000; ++i) {
    const double amplitude = 1.0e6 * (1.0 - i / 1000.0);
    s.update(f, 1.0e6 + ((i % 2 == 0) ? amplitude : -amplitude));
  }
  EXPECT_GE(s.turning_points(), PreisachState::kCapacity - 1);  // full (a merge frees two)
  EXPECT_LE(s.turning_points(), PreisachState::kCapacity);
  EXPECT_GT(s.output(), -1.0);
  EXPECT_LT(s.output(), 1.0);
  // The dominant maximum is remembered: returning to it closes every inner loop.
  EXPECT_NEAR(s.update(f, 2.0e6), first_max, 1e-12);
  EXPECT_EQ(s.turning_points(), 2U);
  EXPECT_DOUBLE_EQ(s.update(f, 3.0e6), 1.0);
  EXPECT_DOUBLE_EQ(s.update(f, -1.0e6), -1.0);
  EXPECT_EQ(s.turning_points(), 1U);
}

}  // namespace
}  // namespace selfsense::plant
