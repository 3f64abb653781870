// The loop's health state (Loop::kHealthStateSize values: the estimate's baseline, trends and
// counts, then the alarms' latches and raise times) saved by kSaveState and restored into a new
// loop before its first cycle: saved again, the values are the same bit for bit, and the
// figures, the latched warning and its raise time are the same in the status.
#include <gtest/gtest.h>

#include <array>
#include <vector>

#include "health_bench.hpp"

namespace selfsense::runtime {
namespace {

using test::HealthBench;

constexpr auto kOverheatingIndex = static_cast<std::size_t>(adaptation::HealthAlarm::kOverheating);

test::HealthBenchOptions options() {
  test::HealthBenchOptions o;
  o.temperature = {25.0, 45.0, 20.0, 0.0, 600.0};
  o.loop = test::health_loop_config();
  o.loop.health.settle_s = 5.0;
  o.loop.health.baseline_cycles = 5;
  o.loop.health_bands.max_temperature_degc = 30.0;
  return o;
}

std::vector<double> save(HealthBench& b, CommandResult expected = CommandResult::kDone) {
  models::SavedState model = adaptation::AdaptedReconstruction(
                                 models::load_model(std::filesystem::path(SELFSENSE_SOURCE_DIR) /
                                                    "config/models/sim.yaml"),
                                 {}, test::kHealthTs)
                                 .make_saved_state();
  std::vector<double> health(b.loop->health_state_size(), 0.0);
  LoopCommand c{0, CommandKind::kSaveState};
  c.state = &model;
  c.health_state = health;
  EXPECT_EQ(b.send(c), expected);
  return health;
}

// Before the loop's first cycle (the daemon's socket may answer then) the status says what is
// configured: health and adaptation on, nothing measured yet, no alarm. It used to be the
// default snapshot, which said health and adaptation were off.
TEST(LoopHealthState, BeforeTheFirstCycleTheStatusSaysWhatIsConfigured) {
  const HealthBench b(options());
  const StatusSnapshot s = b.loop->status();
  EXPECT_EQ(s.cycle, 0);
  EXPECT_TRUE(s.adaptation.enabled);
  EXPECT_EQ(s.adaptation.updates, 0U);
  EXPECT_TRUE(s.health.enabled);
  EXPECT_FALSE(s.health.fault);
  const adaptation::HealthFigures& f = s.health.figures;
  EXPECT_FALSE(f.has_capacitance || f.has_dissipation || f.has_depolarisation || f.has_leakage);
  EXPECT_FALSE(f.baseline_ready);
  EXPECT_EQ(f.cycles + f.compared_cycles + f.holds, 0U);
  EXPECT_EQ(s.health.active | s.health.latched, 0U);
  for (const double t : s.health.raised_at_s)
    EXPECT_LT(t, 0.0);
}

TEST(LoopHealthState, SavedAndRestoredIntoANewLoopBitForBit) {
  HealthBench first(options());
  first.run(0.1);
  ASSERT_EQ(first.send({0, CommandKind::kReset}), CommandResult::kDone);
  ASSERT_EQ(first.send({0, CommandKind::kArm}), CommandResult::kDone);
  first.wave(test::strain_sine());
  first.run(30.0);
  const HealthStatus before = first.health();
  ASSERT_TRUE(before.figures.baseline_ready);
  ASSERT_GT(before.figures.compared_cycles, 10U);
  ASSERT_NE(before.latched & adaptation::bit(adaptation::HealthAlarm::kOverheating), 0U);
  const std::vector<double> saved = save(first);
  ASSERT_EQ(saved.size(), Loop::kHealthStateSize);

  HealthBench second(options());
  EXPECT_FALSE(second.loop->restore_health_state(std::span(saved).first(saved.size() - 1)));
  ASSERT_TRUE(second.loop->restore_health_state(saved));
  const HealthStatus& after = second.loop->status().health;
  EXPECT_EQ(after.figures.baseline_ready, true);
  EXPECT_EQ(after.figures.cycles, before.figures.cycles);
  EXPECT_EQ(after.figures.compared_cycles, before.figures.compared_cycles);
  EXPECT_EQ(after.figures.capacitance_f_per_m,
            first.loop->status().health.figures.capacitance_f_per_m);
  EXPECT_EQ(after.latched, before.latched);
  EXPECT_EQ(after.raised_at_s[kOverheatingIndex], before.raised_at_s[kOverheatingIndex]);
  // The first cycle's command is the save: nothing has been measured since the restore.
  EXPECT_EQ(save(second), saved);

  // A buffer of the wrong size: refused, nothing written.
  LoopCommand c{0, CommandKind::kSaveState};
  models::SavedState model;
  std::array<double, 3> small{};
  c.state = &model;
  c.health_state = small;
  EXPECT_EQ(second.send(c), CommandResult::kInvalid);
}

}  // namespace
}  // namespace selfsense::runtime
