// SetpointShaper: slew limit, first- and second-order filters, bumpless reset.
#include "selfsense/control/setpoint_shaper.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace selfsense::control {
namespace {

constexpr double kTs = 1e-3;
using Filter = SetpointShaper::Filter;

TEST(SetpointShaper, SlewLimitRampsAtTheRate) {
  SetpointShaper shaper({.slew_rate = 10.0}, kTs);  // 0.01 per sample
  shaper.reset(0.0);
  for (int k = 1; k <= 100; ++k)
    ASSERT_NEAR(shaper.step(1.0), 0.01 * k, 1e-12) << k;
  EXPECT_EQ(shaper.step(1.0), 1.0);
  EXPECT_NEAR(shaper.step(0.995), 0.995, 1e-15);  // small moves pass unlimited
}

TEST(SetpointShaper, WithoutLimitOrFilterItPassesThrough) {
  SetpointShaper shaper({}, kTs);
  EXPECT_EQ(shaper.step(3.5), 3.5);
  EXPECT_EQ(shaper.step(-2.0), -2.0);
}

TEST(SetpointShaper, FirstOrderFilterIsTheExactSampledLag) {
  const double tau = 0.02;
  SetpointShaper shaper({.filter = Filter::kFirstOrder, .time_constant = tau}, kTs);
  shaper.reset(0.0);
  for (int k = 1; k <= 200; ++k) {
    ASSERT_NEAR(shaper.step(1.0), 1.0 - std::exp(-k * kTs / tau), 1e-12) << k;
  }
}

TEST(SetpointShaper, SecondOrderFilterIsCriticallyDampedWithoutOvershoot) {
  const double tau = 0.01;
  SetpointShaper shaper({.filter = Filter::kSecondOrder, .time_constant = tau}, kTs);
  shaper.reset(0.0);
  double previous = 0.0;
  for (int k = 1; k <= 300; ++k) {
    const double y = shaper.step(1.0);
    ASSERT_GE(y, previous) << k;
    ASSERT_LE(y, 1.0) << k;
    // Two exact lags in series, a double pole at r = 1 - a:
    //   y[k] = 1 - r^k (1 + k a),  a = 1 - exp(-Ts / tau),
    // within a of the continuous 1 - (1 + t/tau) exp(-t/tau).
    const double a = 1.0 - std::exp(-kTs / tau);
    EXPECT_NEAR(y, 1.0 - std::pow(1.0 - a, k) * (1.0 + k * a), 1e-12) << k;
    const double t = k * kTs;
    EXPECT_NEAR(y, 1.0 - (1.0 + t / tau) * std::exp(-t / tau), a) << k;
    previous = y;
  }
  EXPECT_NEAR(previous, 1.0, 1e-9);
}

TEST(SetpointShaper, FilteredOutputNeverMovesFasterThanTheSlewRate) {
  const double rate = 5.0;
  SetpointShaper shaper({.slew_rate = rate, .filter = Filter::kSecondOrder, .time_constant = 0.005},
                        kTs);
  shaper.reset(0.0);
  double previous = 0.0;
  for (int k = 0; k < 2000; ++k) {
    const double target = (k / 300) % 2 == 0 ? 1.0 : -1.0;
    const double y = shaper.step(target);
    ASSERT_LE(std::abs(y - previous), rate * kTs * (1.0 + 1e-12)) << k;
    previous = y;
  }
}

TEST(SetpointShaper, ResetStartsAtTheMeasuredState) {
  SetpointShaper shaper({.slew_rate = 1.0, .filter = Filter::kSecondOrder, .time_constant = 0.05},
                        kTs);
  shaper.step(5.0);
  shaper.reset(0.37);
  EXPECT_EQ(shaper.step(0.37), 0.37);
  EXPECT_EQ(shaper.output(), 0.37);
}

}  // namespace
}  // namespace selfsense::control
