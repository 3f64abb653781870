// Pid: step responses against analytic results, derivative filter, bumpless transfer.
#include "selfsense/control/pid.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "control/simulated_plants.hpp"

namespace selfsense::control {
namespace {

constexpr double kTs = 1e-4;

Pid::Params pi_params(double kp, double ki) {
  Pid::Params p;
  p.gains = {kp, ki, 0.0};
  return p;
}

TEST(Pid, PiStepResponseIsTheSampledAnalyticOne) {
  // Constant r and y: u[k] = kp (b r - y) + ki Ts k (r - y), the forward-Euler integral.
  Pid::Params p = pi_params(0.8, 50.0);
  p.setpoint_weight = 0.5;
  Pid pid(p, kTs);
  const double r = 2.0;
  const double y = 0.5;
  for (int k = 0; k < 2000; ++k) {
    const double expected = 0.8 * (0.5 * r - y) + 50.0 * kTs * k * (r - y);
    ASSERT_NEAR(pid.step(r, y), expected, 1e-12) << "sample " << k;
  }
}

TEST(Pid, PiOnAFirstOrderPlantReachesTheSetpointAndIntegratesTheError) {
  const double plant_gain = 2.0;
  test::FirstOrderPlant plant(plant_gain, 0.01, kTs);
  Pid pid(pi_params(0.5, 100.0), kTs);
  const double r = 1.0;
  double error_sum = 0.0;
  for (int k = 0; k < 20000; ++k) {
    const double y = plant.output();
    error_sum += r - y;
    plant.advance(pid.step(r, y));
  }
  EXPECT_NEAR(plant.output(), r, 1e-9);
  // At rest the integral term alone holds the plant at r: u = r / K.
  EXPECT_NEAR(pid.integral(), r / plant_gain, 1e-9);
  EXPECT_NEAR(pid.output(), r / plant_gain, 1e-9);
  // Without limits the integral term is ki Ts times the sum of the errors.
  EXPECT_NEAR(pid.integral(), 100.0 * kTs * error_sum, 1e-9);
}

TEST(Pid, SetpointWeightScalesOnlyTheProportionalJump) {
  Pid::Params p = pi_params(2.0, 10.0);
  p.setpoint_weight = 0.25;
  Pid pid(p, kTs);
  // First sample: I = 0, D = 0, so u = kp (b r - y).
  EXPECT_DOUBLE_EQ(pid.step(4.0, 1.0), 2.0 * (0.25 * 4.0 - 1.0));
}

TEST(Pid, SetpointStepGivesNoDerivativeKick) {
  Pid::Params p;
  p.gains = {1.0, 0.0, 0.5};
  p.derivative_filter_time = 1e-3;
  Pid pid(p, kTs);
  for (int k = 0; k < 10; ++k)
    pid.step(0.0, 0.3);
  const double u = pid.step(1.0, 0.3);
  EXPECT_EQ(pid.derivative(), 0.0);
  EXPECT_DOUBLE_EQ(u, 1.0 * (1.0 - 0.3));
}

TEST(Pid, DerivativeOfARampSettlesAtMinusKdTimesTheSlope) {
  Pid::Params p;
  p.gains = {0.0, 0.0, 0.2};
  p.derivative_filter_time = 5e-4;
  Pid pid(p, kTs);
  const double slope = 3.0;  // [x/s]
  for (int k = 0; k < 1000; ++k)
    pid.step(0.0, slope * kTs * k);
  EXPECT_NEAR(pid.derivative(), -0.2 * slope, 1e-9);
}

TEST(Pid, DerivativeFilterAttenuatesAtNyquistAsDesigned) {
  // y alternating +-1 is the Nyquist frequency; |D| -> 2 kd / (2 Tf + Ts).
  const double kd = 0.01;
  const double tf = 4e-4;
  Pid::Params p;
  p.gains = {0.0, 0.0, kd};
  p.derivative_filter_time = tf;
  Pid filtered(p, kTs);
  p.derivative_filter_time = 0.0;
  Pid raw(p, kTs);
  double last_filtered = 0.0;
  double last_raw = 0.0;
  for (int k = 0; k < 400; ++k) {
    const double y = (k % 2 == 0) ? 1.0 : -1.0;
    last_filtered = filtered.step(0.0, y);
    last_raw = raw.step(0.0, y);
  }
  const double expected = 2.0 * kd / (2.0 * tf + kTs);
  EXPECT_NEAR(std::abs(last_filtered), expected, 1e-12);
  EXPECT_DOUBLE_EQ(filtered.derivative_nyquist_gain(), expected);
  EXPECT_NEAR(std::abs(last_raw), 2.0 * kd / kTs, 1e-9);
  // Attenuation against the plain difference: Ts / (2 Tf + Ts) = 1/9 here.
  EXPECT_NEAR(std::abs(last_filtered / last_raw), kTs / (2.0 * tf + kTs), 1e-12);
}

TEST(Pid, FilterTimeFromN) {
  // Tf = kd / (kp N) = 0.01 / (2 * 10) = 5e-4.
  Pid::Params p;
  p.gains = {2.0, 0.0, 0.01};
  p.derivative_filter_n = 10.0;
  const Pid pid(p, kTs);
  EXPECT_DOUBLE_EQ(pid.derivative_nyquist_gain(), 2.0 * 0.01 / (2.0 * 5e-4 + kTs));
}

TEST(Pid, FeedforwardIsAddedBeforeTheLimits) {
  Pid::Params p = pi_params(1.0, 0.0);
  p.output_min = -1.0;
  p.output_max = 1.0;
  Pid pid(p, kTs);
  EXPECT_DOUBLE_EQ(pid.step(0.5, 0.0, 0.25), 0.75);
  EXPECT_DOUBLE_EQ(pid.step(0.5, 0.0, 0.75), 1.0);
}

Pid::Params full_params() {
  Pid::Params p;
  p.gains = {1.5, 80.0, 0.002};
  p.setpoint_weight = 0.6;
  p.derivative_filter_time = 3e-4;
  p.output_min = -5.0;
  p.output_max = 5.0;
  p.tracking_time = 2e-3;
  return p;
}

TEST(Pid, ResetBumplessContinuesFromTheAppliedOutput) {
  Pid pid(full_params(), kTs);
  for (int k = 0; k < 50; ++k)
    pid.step(1.0, 0.1 * k);
  // Arm at the measured state with 1.7 already applied by another mode.
  pid.reset_bumpless(0.42, 1.7);
  EXPECT_DOUBLE_EQ(pid.step(0.42, 0.42), 1.7);

  pid.reset_bumpless(0.42, -0.3, 0.5, 0.2);
  EXPECT_DOUBLE_EQ(pid.step(0.5, 0.42, 0.2), -0.3);
}

TEST(Pid, GainChangeDoesNotBumpTheOutput) {
  Pid reference(full_params(), kTs);
  Pid::Params n_params = full_params();
  n_params.derivative_filter_n = 8.0;  // Tf follows the gains: ad changes too
  Pid reference_n(n_params, kTs);
  std::vector<double> y(300);
  for (std::size_t k = 0; k < y.size(); ++k)
    y[k] = 0.5 * std::sin(0.05 * static_cast<double>(k));
  for (std::size_t k = 0; k + 1 < y.size(); ++k) {
    reference.step(1.0, y[k]);
    reference_n.step(1.0, y[k]);
  }
  for (Pid* pid : {&reference, &reference_n}) {
    Pid changed = *pid;
    ASSERT_TRUE(changed.set_gains({4.0, 10.0, 0.004}));
    // Same inputs again: what the old gains would give now is what the new ones give.
    const double r = 1.0;
    const double last_y = y[y.size() - 2];
    EXPECT_NEAR(changed.step(r, last_y), pid->step(r, last_y), 1e-12);
  }
}

TEST(Pid, SetGainsRejectsUnusableGainsAndChangesNothing) {
  Pid::Params p = full_params();
  p.derivative_filter_n = 8.0;
  Pid pid(p, kTs);
  EXPECT_FALSE(pid.set_gains({-1.0, 1.0, 0.0}));
  EXPECT_FALSE(pid.set_gains({1.0, std::nan(""), 0.0}));
  EXPECT_FALSE(pid.set_gains({0.0, 1.0, 0.01}));  // N needs kp > 0
  EXPECT_EQ(pid.params().gains.kp, 1.5);
}

TEST(Pid, TrackMakesTheIntegratorFollowAnOverriddenOutput) {
  // Tt = 0: the integrator takes the whole difference, so the next output at unchanged inputs
  // is the applied one plus this sample's integration.
  Pid::Params p = pi_params(1.0, 20.0);
  Pid pid(p, kTs);
  const double u = pid.step(1.0, 0.0);
  EXPECT_DOUBLE_EQ(u, 1.0);
  pid.track(0.25);
  EXPECT_DOUBLE_EQ(pid.output(), 0.25);
  EXPECT_NEAR(pid.step(1.0, 0.0), 0.25 + 20.0 * kTs * 1.0, 1e-15);
}

// A reload narrows the output range while running: the next output is clamped to it; invalid
// limits change nothing.
TEST(Pid, OutputLimitsChangeWhileRunning) {
  Pid::Params p;
  p.gains = {2.0, 0.0, 0.0};
  Pid pid(p, 1e-3);
  EXPECT_EQ(pid.step(10.0, 0.0), 20.0);
  ASSERT_TRUE(pid.set_output_limits(-5.0, 5.0));
  EXPECT_EQ(pid.step(10.0, 0.0), 5.0);
  EXPECT_FALSE(pid.set_output_limits(1.0, 1.0));
  EXPECT_FALSE(pid.set_output_limits(std::nan(""), 1.0));
  EXPECT_EQ(pid.params().output_max, 5.0);
  EXPECT_EQ(pid.step(-10.0, 0.0), -5.0);
}

}  // namespace
}  // namespace selfsense::control
