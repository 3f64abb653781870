// Pid anti-windup: after a long saturation the overshoot stays bounded, by back-calculation,
// by conditional integration, and through track() when the amplifier limits the output.
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>

#include "control/simulated_plants.hpp"
#include "selfsense/control/pid.hpp"

namespace selfsense::control {
namespace {

constexpr double kTs = 1e-4;

// PI (kp = 5, Ti = 0.5 s) on y' = (u - y) / 1 s, output limited to [-1.5, 1.5]: a unit setpoint
// step saturates the output for about a second, long enough to wind an integrator up.
Pid::Params windup_prone(double tracking_time, bool conditional) {
  Pid::Params p;
  p.gains = {5.0, 10.0, 0.0};
  p.output_min = -1.5;
  p.output_max = 1.5;
  p.tracking_time = tracking_time;
  p.conditional_integration = conditional;
  return p;
}

// Peak of y above the unit setpoint over 10 s. `amplifier_limit` clips what reaches the plant;
// with `track` the controller is told the clipped value.
double overshoot(const Pid::Params& params, double amplifier_limit, bool track) {
  Pid pid(params, kTs);
  test::FirstOrderPlant plant(1.0, 1.0, kTs);
  double peak = 0.0;
  for (int k = 0; k < 100000; ++k) {
    const double u = pid.step(1.0, plant.output());
    const double applied = std::clamp(u, -amplifier_limit, amplifier_limit);
    if (track) pid.track(applied);
    plant.advance(applied);
    peak = std::max(peak, plant.output());
  }
  return peak - 1.0;
}

constexpr double kNoClip = std::numeric_limits<double>::infinity();

TEST(PidAntiWindup, WithoutAntiWindupTheOvershootIsLarge) {
  EXPECT_GT(overshoot(windup_prone(0.0, false), kNoClip, false), 0.25);
}

TEST(PidAntiWindup, BackCalculationBoundsTheOvershoot) {
  const double wound = overshoot(windup_prone(0.0, false), kNoClip, false);
  const double back_calculation = overshoot(windup_prone(1e-2, false), kNoClip, false);
  EXPECT_LT(back_calculation, 0.01);
  EXPECT_LT(back_calculation, 0.05 * wound);
}

TEST(PidAntiWindup, ConditionalIntegrationBoundsTheOvershoot) {
  const double wound = overshoot(windup_prone(0.0, false), kNoClip, false);
  const double conditional = overshoot(windup_prone(0.0, true), kNoClip, false);
  EXPECT_LT(conditional, 0.01);
  EXPECT_LT(conditional, 0.05 * wound);
  EXPECT_LT(overshoot(windup_prone(1e-2, true), kNoClip, false), 0.01);
}

TEST(PidAntiWindup, TrackFollowsTheAmplifiersLimit) {
  // The controller's own limits are wide; the amplifier clips at 1.5. Without track() the
  // integrator winds up against a limit it does not know.
  Pid::Params wide = windup_prone(1e-2, true);
  wide.output_min = -100.0;
  wide.output_max = 100.0;
  const double blind = overshoot(wide, 1.5, false);
  const double tracked = overshoot(wide, 1.5, true);
  EXPECT_GT(blind, 0.25);
  EXPECT_LT(tracked, 0.01);
}

}  // namespace
}  // namespace selfsense::control
