#include "selfsense/operators/play.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "support/random_walk.hpp"

namespace selfsense::operators {
namespace {

TEST(PlayOperator, FollowsTheBacklashDifferenceEquation) {
  PlayOperator play(1.0);
  EXPECT_DOUBLE_EQ(play.step(0.5), 0.0);   // inside the band: holds
  EXPECT_DOUBLE_EQ(play.step(3.0), 2.0);   // pushed up: x - r
  EXPECT_DOUBLE_EQ(play.step(2.5), 2.0);   // reversal inside the band
  EXPECT_DOUBLE_EQ(play.step(-1.0), 0.0);  // pushed down: x + r
}

TEST(PlayOperator, RemanentInitialStateIsKept) {
  PlayOperator play(1.0, 0.7);
  EXPECT_DOUBLE_EQ(play.step(0.0), 0.7);
  play.set_output(-0.4);
  EXPECT_DOUBLE_EQ(play.output(), -0.4);
  EXPECT_DOUBLE_EQ(play.step(0.2), -0.4);
}

TEST(StopOperator, IsInputMinusPlay) {
  const std::vector<double> x = test::random_walk(5000, -3.0, 3.0, 0.2, 7);
  PlayOperator play(0.8);
  StopOperator stop(0.8);
  for (const double v : x) {
    const double p = play.step(v);
    const double e = stop.step(v);
    ASSERT_NEAR(p + e, v, 1e-12);
    ASSERT_LE(std::abs(e), 0.8 + 1e-12);
  }
}

TEST(StopOperator, StateIsInputAndOutput) {
  StopOperator stop(1.0, 2.0, 0.5);
  EXPECT_DOUBLE_EQ(stop.output(), 0.5);
  EXPECT_DOUBLE_EQ(stop.step(2.3), 0.8);  // e + dx
  EXPECT_DOUBLE_EQ(stop.step(3.0), 1.0);  // saturates at r
}

TEST(PlayOperator, BatchEqualsSteps) {
  const std::vector<double> x = test::random_walk(1000, -1.0, 1.0, 0.1);
  PlayOperator a(0.3);
  PlayOperator b(0.3);
  std::vector<double> y(x.size());
  a.apply(x, y);
  for (std::size_t k = 0; k < x.size(); ++k)
    ASSERT_EQ(y[k], b.step(x[k]));
}

}  // namespace
}  // namespace selfsense::operators
