// The loss of polarisation under closed position control (issue 24, docs/health.md): the loop
// tracks a strain sine on the self-sensed strain while the stack loses 5 % of its polarisation
// over an hour (plant.aging); the controller raises the field to make up the lost stroke, so the
// cycles' field extremes move away from the baseline's and the larger field's larger loop hides
// the loss. The estimate compares each cycle's loop with the model's predicted loop for the same
// field path (HealthEstimatorConfig::model_reference) and follows the planted loss; compared
// with the baseline's loop at (nearly) the baseline's extremes, it reads about half of it.
// The bench of health_bench.hpp (1 kHz, the daemon's stack without its resonance), 30 degC.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "health_bench.hpp"

namespace selfsense::runtime {
namespace {

constexpr double kStart = 120.0;  // aging starts: the baseline is set before
constexpr double kLossPerH = 0.05;

struct PositionRun {
  double max_error{0.0};  // largest |estimate - true loss| from 10 min on [1]
  double final_estimate{0.0};
  double final_truth{0.0};
  std::uint64_t compared_at_10min{0};
  std::uint64_t compared_at_end{0};
  std::uint32_t faults{0};
  double e_max_start{0.0};  // the field's largest value in the 5th minute [V/m]
  double e_max_end{0.0};    // in the last
};

PositionRun run_position_hour(bool model_reference) {
  test::HealthBenchOptions o;
  o.temperature = {30.0, 30.0, 0.0, 0.0, 600.0};
  o.polarisation_loss_per_h = kLossPerH;
  o.aging_start_s = kStart;
  o.mode = ControlMode::kPosition;
  o.loop = test::health_loop_config();
  o.loop.health.model_reference = model_reference;
  test::HealthBench b(o);
  b.run(0.1);
  EXPECT_EQ(b.send({0, CommandKind::kReset}), CommandResult::kDone);
  EXPECT_EQ(b.send({0, CommandKind::kArm}), CommandResult::kDone);
  b.wave(test::strain_sine());
  PositionRun out;
  const double end_s = kStart + 3600.0;
  for (double t = 60.0; t <= end_s + 1e-9; t += 60.0) {
    double e_max = 0.0;  // the field's largest value in this minute [V/m]
    for (int k = 0; k < 60000; ++k) {
      b.loop->cycle(false);
      e_max = std::max(e_max, b.loop->local_status().last.e);
    }
    if (std::abs(t - 300.0) < 1.0) out.e_max_start = e_max;
    out.e_max_end = e_max;
    const adaptation::HealthFigures& f = b.health().figures;
    const double truth = std::max(0.0, kLossPerH * (t - kStart) / 3600.0);
    if (t >= 600.0) out.max_error = std::max(out.max_error, std::abs(f.depolarisation - truth));
    if (std::abs(t - 600.0) < 1.0) out.compared_at_10min = f.compared_cycles;
    if (std::fmod(t, 600.0) < 1.0) {
      std::printf("t %5.0f s  true %5.2f %%  estimate %6.3f %%  compared %llu  E_max %.4e\n", t,
                  100.0 * truth, 100.0 * f.depolarisation,
                  static_cast<unsigned long long>(f.compared_cycles), e_max);
    }
    out.final_estimate = f.depolarisation;
    out.final_truth = truth;
    out.compared_at_end = f.compared_cycles;
  }
  out.faults = b.loop->local_status().faults;
  return out;
}

TEST(HealthPosition, TheLossFollowsThePlantedLossUnderPositionControl) {
  const PositionRun run = run_position_hour(true);
  std::printf(
      "model reference: max |error| %.3f %% (from 10 min), final %.3f %% (true %.2f %%), "
      "largest field %.4e -> %.4e V/m\n",
      100.0 * run.max_error, 100.0 * run.final_estimate, 100.0 * run.final_truth, run.e_max_start,
      run.e_max_end);
  EXPECT_GT(run.e_max_end, run.e_max_start);  // the loop raised the field
  EXPECT_EQ(run.faults, 0U);
  EXPECT_GT(run.compared_at_end, run.compared_at_10min + 5000U);  // it kept comparing
  // Measured 5.19 % for 5 %, and 0.44 % of polarisation at most from 10 min on.
  EXPECT_NEAR(run.final_estimate, run.final_truth, 0.0025);
  EXPECT_LT(run.max_error, 0.006);
}

TEST(HealthPosition, AgainstTheBaselinesLoopAloneItReadsAboutHalf) {
  const PositionRun run = run_position_hour(false);
  std::printf("extremes only: max |error| %.3f %% (from 10 min), final %.3f %% (true %.2f %%)\n",
              100.0 * run.max_error, 100.0 * run.final_estimate, 100.0 * run.final_truth);
  EXPECT_GT(run.final_truth - run.final_estimate, 0.018);  // measured 2.59 % for 5 %
}

}  // namespace
}  // namespace selfsense::runtime
