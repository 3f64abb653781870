// DampingController on a simulated lightly damped mode: the ring-down gets much shorter.
#include "selfsense/control/damping_controller.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <optional>
#include <vector>

#include "control/simulated_plants.hpp"

namespace selfsense::control {
namespace {

constexpr double kTs = 1.0 / 20000.0;
constexpr double kResonance = 500.0;  // [Hz]
constexpr double kPlantDamping = 0.005;

using Law = DampingController::Law;

// Time for the free vibration from x = 1 to stay within 5 %, with or without the controller in
// the loop (collocated: it measures x and its output adds to the plant input).
double ring_down(std::optional<DampingController> controller) {
  test::ResonantPlant plant(kResonance, kPlantDamping, kTs);
  plant.set_position(1.0);
  std::vector<double> x(20000);  // 1 s
  for (double& xk : x) {
    xk = plant.position();
    plant.advance(controller ? controller->step(xk) : 0.0);
  }
  return test::settle_time(x, 0.05, kTs);
}

TEST(DampingController, UndampedRingDownMatchesTheModalDecay) {
  // |x| ~ exp(-zeta w t): 5 % after ln(20) / (zeta w) = 0.19 s.
  const double expected = std::log(20.0) / (kPlantDamping * 2.0 * std::numbers::pi * kResonance);
  EXPECT_NEAR(ring_down(std::nullopt), expected, 0.01);
}

TEST(DampingController, PositivePositionFeedbackShortensTheRingDownFivefold) {
  const DampingController ppf(
      {.law = Law::kPositivePosition, .gain = 0.5, .frequency = kResonance, .damping = 0.3}, kTs);
  const double undamped = ring_down(std::nullopt);
  const double damped = ring_down(ppf);
  EXPECT_GT(damped, 0.0);
  EXPECT_LE(damped * 5.0, undamped) << "damped " << damped << " s, undamped " << undamped << " s";
}

TEST(DampingController, VelocityFeedbackShortensTheRingDownFivefold) {
  // u = -g v adds 2 zeta w = g w^2 of damping: g = 0.2 / w gives zeta + 0.1.
  const double w = 2.0 * std::numbers::pi * kResonance;
  const DampingController velocity({.law = Law::kVelocity, .gain = 0.2 / w, .frequency = 5000.0},
                                   kTs);
  const double undamped = ring_down(std::nullopt);
  const double damped = ring_down(velocity);
  EXPECT_GT(damped, 0.0);
  EXPECT_LE(damped * 5.0, undamped) << "damped " << damped << " s, undamped " << undamped << " s";
}

TEST(DampingController, DcBlockKeepsPpfOffAStaticBias) {
  // The mode is held at x = 1 by a constant drive of 1 (a biased actuator) and released from
  // x = 1.5. PPF alone feeds the bias back too and moves the rest position to 1 / (1 - g) = 2;
  // with a 20 Hz high-pass in front the rest position stays at 1 and the ring-down is as short.
  const auto run = [](double dc_block_frequency, double* rest) {
    DampingController ppf({.gain = 0.5,
                           .frequency = kResonance,
                           .damping = 0.3,
                           .dc_block_frequency = dc_block_frequency},
                          kTs);
    ppf.reset(1.0);
    test::ResonantPlant plant(kResonance, kPlantDamping, kTs);
    plant.set_position(1.5);
    std::vector<double> deviation(20000);
    for (double& d : deviation) {
      d = plant.position() - 1.0;
      plant.advance(1.0 + ppf.step(plant.position()));
    }
    *rest = plant.position();
    return test::settle_time(deviation, 0.025, kTs);
  };
  double rest_plain = 0.0;
  double rest_blocked = 0.0;
  run(0.0, &rest_plain);
  const double ring_blocked = run(20.0, &rest_blocked);
  EXPECT_NEAR(rest_plain, 2.0, 1e-3);
  EXPECT_NEAR(rest_blocked, 1.0, 1e-3);
  EXPECT_LE(ring_blocked * 5.0, ring_down(std::nullopt));
}

TEST(DampingController, PpfPassesDcWithItsGainAndVelocityFeedbackBlocksIt) {
  DampingController ppf({.gain = 0.5, .frequency = kResonance}, kTs);
  ppf.reset(2.0);
  EXPECT_NEAR(ppf.step(2.0), 1.0, 1e-12);
  DampingController velocity({.law = Law::kVelocity, .gain = 1.0, .frequency = 2000.0}, kTs);
  velocity.reset(2.0);
  EXPECT_NEAR(velocity.step(2.0), 0.0, 1e-12);
  DampingController blocked({.gain = 0.5, .frequency = kResonance, .dc_block_frequency = 10.0},
                            kTs);
  blocked.reset(2.0);
  EXPECT_NEAR(blocked.step(2.0), 0.0, 1e-12);
  // A ramp gives -g * slope after the filter settles.
  for (int k = 0; k < 2000; ++k)
    velocity.step(3.0 * kTs * k);
  EXPECT_NEAR(velocity.step(3.0 * kTs * 2000), -3.0, 1e-6);
}

TEST(DampingController, OutputIsLimited) {
  DampingController ppf({.gain = 0.5, .frequency = kResonance, .output_limit = 0.1}, kTs);
  ppf.reset(10.0);
  EXPECT_EQ(ppf.step(10.0), 0.1);
  ppf.reset(-10.0);
  EXPECT_EQ(ppf.step(-10.0), -0.1);
}

}  // namespace
}  // namespace selfsense::control
