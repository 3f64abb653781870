// `ctl reset` and the health warnings: a reset the loop refuses changes nothing, not the
// supervisor and not a latched warning; one it answers kDone clears what it says.
// The overheating warning is latched by a plant whose temperature swings 25 +- 15 K (period
// 40 s) under an open-loop sine: the adaptation's equivalent temperature crosses a band of
// 32 degC on the way up and falls back inside it on the way down.
#include <gtest/gtest.h>

#include "health_bench.hpp"

namespace selfsense::runtime {
namespace {

using test::HealthBench;

constexpr std::uint32_t kOverheating = adaptation::bit(adaptation::HealthAlarm::kOverheating);
constexpr auto kOverheatingIndex = static_cast<std::size_t>(adaptation::HealthAlarm::kOverheating);

// Runs until the overheating warning is latched and back inside its band (at most `limit_s`).
bool run_until_clearable(HealthBench& b, double limit_s) {
  for (double t = 0.0; t < limit_s; t += 0.1) {
    b.run(0.1);
    const HealthStatus& h = b.health();
    if ((h.latched & kOverheating) != 0U && (h.active & kOverheating) == 0U) return true;
  }
  return false;
}

TEST(LoopReset, ARefusedResetClearsNoWarning) {
  test::HealthBenchOptions o;
  o.temperature = {25.0, 25.0, 0.0, 15.0, 40.0};
  o.loop = test::health_loop_config();
  o.loop.health_bands.max_temperature_degc = 32.0;
  HealthBench b(o);
  b.run(0.1);
  ASSERT_EQ(b.send({0, CommandKind::kReset}), CommandResult::kDone);  // power_up
  // Ready, nothing latched: nothing to reset.
  EXPECT_EQ(b.send({0, CommandKind::kReset}), CommandResult::kRefusedState);
  ASSERT_EQ(b.send({0, CommandKind::kArm}), CommandResult::kDone);
  b.wave(test::strain_sine());
  ASSERT_TRUE(run_until_clearable(b, 40.0));
  const double raised = b.health().raised_at_s[kOverheatingIndex];
  ASSERT_GE(raised, 0.0);

  // Faulted with the cause present: refused, and the warning stays latched.
  ASSERT_TRUE(b.driver.inject(plant::FaultKind::nan_sample, plant::Channel::d, 0, 500));
  b.run(0.1);
  ASSERT_EQ(b.loop->supervisor().state(), LoopState::kFaulted);
  EXPECT_EQ(b.send({0, CommandKind::kReset}), CommandResult::kRefusedCause);
  b.run(0.1);  // the next status snapshot
  EXPECT_EQ(b.loop->supervisor().state(), LoopState::kFaulted);
  EXPECT_NE(b.health().latched & kOverheating, 0U);
  EXPECT_EQ(b.health().raised_at_s[kOverheatingIndex], raised);

  // The cause is over: the reset clears the fault and the warning back inside its band.
  b.run(0.5);
  EXPECT_EQ(b.send({0, CommandKind::kReset}), CommandResult::kDone);
  b.run(0.1);
  EXPECT_EQ(b.loop->supervisor().state(), LoopState::kReady);
  EXPECT_EQ(b.health().latched & kOverheating, 0U);
  EXPECT_LT(b.health().raised_at_s[kOverheatingIndex], 0.0);

  // Armed, the warning latched again and still beyond its band: refused, nothing cleared.
  ASSERT_EQ(b.send({0, CommandKind::kArm}), CommandResult::kDone);
  b.wave(test::strain_sine());
  bool active = false;
  for (double t = 0.0; t < 40.0 && !active; t += 0.1) {
    b.run(0.1);
    active = (b.health().active & kOverheating) != 0U;
  }
  ASSERT_TRUE(active);
  const double raised_again = b.health().raised_at_s[kOverheatingIndex];
  EXPECT_EQ(b.send({0, CommandKind::kReset}), CommandResult::kRefusedCause);
  b.run(0.1);
  EXPECT_EQ(b.loop->supervisor().state(), LoopState::kArmed);
  EXPECT_NE(b.health().latched & kOverheating, 0U);
  EXPECT_EQ(b.health().raised_at_s[kOverheatingIndex], raised_again);

  // Back inside the band while armed: the reset clears the warning and the loop stays armed.
  ASSERT_TRUE(run_until_clearable(b, 40.0));
  EXPECT_EQ(b.send({0, CommandKind::kReset}), CommandResult::kDone);
  b.run(0.1);
  EXPECT_EQ(b.loop->supervisor().state(), LoopState::kArmed);
  EXPECT_EQ(b.health().latched & kOverheating, 0U);
  EXPECT_EQ(b.loop->local_status().faults, 0U);
}

}  // namespace
}  // namespace selfsense::runtime
