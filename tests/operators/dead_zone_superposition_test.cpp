#include "selfsense/operators/dead_zone_superposition.hpp"

#include <gtest/gtest.h>

namespace selfsense::operators {
namespace {

DeadZoneSuperposition sample() {
  DeadZoneSuperposition::Params s;
  s.linear_weight = 2.0;
  s.upper_thresholds = {1.0, 3.0};
  s.upper_weights = {-1.0, 0.5};
  s.lower_thresholds = {-2.0};
  s.lower_weights = {-1.5};
  return DeadZoneSuperposition(s);
}

TEST(DeadZoneSuperposition, PiecewiseLinearWithTheConfiguredSlopes) {
  const DeadZoneSuperposition s = sample();
  EXPECT_DOUBLE_EQ(s.evaluate(0.0), 0.0);
  EXPECT_DOUBLE_EQ(s.evaluate(0.5), 1.0);    // slope 2
  EXPECT_DOUBLE_EQ(s.evaluate(2.0), 3.0);    // 2 + slope 1 beyond 1
  EXPECT_DOUBLE_EQ(s.evaluate(4.0), 5.5);    // 4 + slope 1.5 beyond 3
  EXPECT_DOUBLE_EQ(s.evaluate(-1.0), -2.0);  // slope 2
  EXPECT_DOUBLE_EQ(s.evaluate(-3.0), -4.5);  // -4 + slope 0.5 below -2
  EXPECT_DOUBLE_EQ(s.slope(2.0), 1.0);
  EXPECT_DOUBLE_EQ(s.slope(-3.0), 0.5);
}

TEST(DeadZoneSuperposition, ClosedFormInverse) {
  const DeadZoneSuperposition s = sample();
  const DeadZoneSuperposition inv = s.inverse();
  for (int k = -1000; k <= 1000; ++k) {
    const double y = 0.01 * k;
    ASSERT_NEAR(inv.evaluate(s.evaluate(y)), y, 1e-12 * (1.0 + std::abs(y)));
  }
}

TEST(DeadZoneSuperposition, DefaultIsIdentity) {
  const DeadZoneSuperposition s;
  EXPECT_DOUBLE_EQ(s.evaluate(-3.25), -3.25);
  EXPECT_EQ(s.size(), 0U);
}

}  // namespace
}  // namespace selfsense::operators
