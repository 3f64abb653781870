// The loop's feedforward with the adapted parameters (LoopConfig::adaptation_feedforward_estimate,
// docs/adaptation.md "The feedforward with the adapted parameters"): without a temperature
// sensor the controller's inverse takes the actuator's scales at the drift estimated from E and
// D when configured; frozen, at the frozen drift; with the key false (the default), or without
// adaptation, the identified actuator (scales 1); at a measured temperature with fitted
// coefficients the adapted scales either way. Simulated time: the daemon's bench and its shipped
// model, warming 25 -> 45 degC while a sine plays in open loop.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <numbers>
#include <string>

#include "loop_commands.hpp"
#include "selfsense/adaptation/adapted_reconstruction.hpp"
#include "selfsense/drivers/sim/simulated_transducer.hpp"
#include "selfsense/runtime/loop.hpp"
#include "support/daemon_plant.hpp"
#include "support/shipped_model.hpp"

namespace selfsense::runtime {
namespace {

constexpr double kRate = 10000.0;
constexpr double kTs = 1.0 / kRate;
constexpr double kSineRange = 3.6e-4;  // the sine's peak to peak [strain]

ControllerConfig open_loop_control() {
  ControllerConfig c;
  c.mode = ControlMode::kOpenLoop;
  c.position.gains = {2e8, 2.5e11, 0.0};
  c.force.gains = {0.005, 10.0, 0.0};
  c.position_shaper.slew_rate = 1.0;  // strain per s: the sine below needs 0.006
  c.command_min = 0.0;
  c.command_max = 2e6;
  return c;
}

struct BenchSetup {
  bool adapt{true};                 // the adapted reconstruction, else the plain one
  bool feedforward_estimate{true};  // LoopConfig::adaptation_feedforward_estimate
  double ramp_s{3.0};               // 25 degC -> end_degc over this [s]
  double end_degc{45.0};
  bool measured{false};  // the driver's temperature into the adaptation, the model with
                         // fitted coefficients
};

models::TransducerModel bench_model(bool coefficients) {
  models::TransducerModel m = test::bench_model();
  if (coefficients) {  // the plant's own coefficients per K (plant::TemperatureConfig)
    models::TemperatureCoefficients t;
    t.sensor = {{4e-3, 0.0}, {-4e-3, 0.0}, {2e-3, 0.0}};
    t.actuator = {{2e-3, 0.0}, {-4e-3, 0.0}, {5e-4, 0.0}};
    m.temperature = t;
  }
  return m;
}

// The daemon's bench with its temperature model, warming by the driver's ramp; the shipped
// model adapted with the bench's mount (config/sim.yaml). `adapted` is the loop's own.
struct WarmingBench {
  explicit WarmingBench(const BenchSetup& setup)
      : driver(plant(), {25.0, setup.end_degc, setup.ramp_s}) {
    std::string why;
    EXPECT_TRUE(driver.configure({kTs}, &why)) << why;
    EXPECT_TRUE(driver.activate(&why)) << why;
    LoopConfig lc;
    lc.sample_time = kTs;
    lc.adaptation_feedforward_estimate = setup.feedforward_estimate;
    lc.adaptation_temperature = setup.measured;
    const models::TransducerModel model = bench_model(setup.measured);
    const Controller controller(open_loop_control(), model.actuator, kTs);
    if (!setup.adapt) {
      loop = std::make_unique<Loop>(
          lc, driver, std::make_unique<models::Reconstruction>(model, models::RuntimeOptions{kTs}),
          controller, nullptr);
      return;
    }
    adaptation::DriftEstimatorConfig ec;
    ec.load_stiffness_ratio = 0.21;
    auto owned = std::make_unique<adaptation::AdaptedReconstruction>(model, ec, kTs);
    adapted = owned.get();
    loop = std::make_unique<Loop>(lc, driver, std::move(owned), controller, nullptr);
  }
  static plant::PlantConfig plant() {
    plant::PlantConfig p = test::daemon_plant(kRate);
    p.temperature.enabled = true;
    return p;
  }
  CommandResult send(LoopCommand c) { return test::send_and_cycle(*loop, next_id, c); }
  // A 5 Hz sine of 1.8e-4 around 6e-4 (the field moves: the estimator learns) for `seconds`;
  // true S against the setpoint over them: its RMS and its mean [strain].
  struct Error {
    double rms{0.0};
    double mean{0.0};
  };
  Error play(double seconds) {
    const auto n = static_cast<std::int64_t>(seconds * kRate);
    double sum = 0.0;
    double sum2 = 0.0;
    for (std::int64_t i = 0; i < n; ++i) {
      const double t = static_cast<double>(played++) * kTs;
      const double r = 6e-4 + 0.5 * kSineRange * std::sin(2.0 * std::numbers::pi * 5.0 * t);
      static_cast<void>(loop->submit({++next_id, CommandKind::kSetpoint, r}));
      loop->cycle(false);
      LoopAnswer a;
      while (loop->take_answer(a)) {
      }
      const LoopSample& s = loop->local_status().last;
      sum += s.s_ref - s.setpoint;
      sum2 += (s.s_ref - s.setpoint) * (s.s_ref - s.setpoint);
    }
    const auto count = static_cast<double>(n);
    return {std::sqrt(sum2 / count), sum / count};
  }
  [[nodiscard]] const Controller& controller() const { return loop->controller(); }

  drivers::SimulatedTransducer driver;
  adaptation::AdaptedReconstruction* adapted{nullptr};
  std::unique_ptr<Loop> loop;
  std::uint64_t next_id{0};
  std::int64_t played{0};
};

void arm(WarmingBench& b) {
  b.play(0.2);
  ASSERT_EQ(b.send({0, CommandKind::kReset}), CommandResult::kDone);
  ASSERT_EQ(b.send({0, CommandKind::kArm}), CommandResult::kDone);
  ASSERT_EQ(b.loop->supervisor().state(), LoopState::kArmed);
}

// Without a temperature channel the estimate from E and D reaches the feedforward: the warmer
// stack's actuator responds more (d +0.2 %/K against the loop's -0.4 %/K), so its response and
// compliance scales rise above 1, and they are the adapted reconstruction's own in that cycle.
TEST(LoopFeedforward, TheEstimatedDriftReachesTheFeedforwardWithoutATemperature) {
  WarmingBench b({});
  arm(b);
  b.play(4.0);
  ASSERT_EQ(b.loop->supervisor().state(), LoopState::kArmed);
  EXPECT_FALSE(b.loop->config().adaptation_temperature);
  const double estimated = b.adapted->drift().temperature_degc;
  EXPECT_GT(estimated, 35.0);  // the drift has moved (the plant is at 45 degC)
  const adaptation::AdaptedReconstruction::FeedforwardScales g = b.adapted->feedforward_scales();
  EXPECT_EQ(b.controller().feedforward_response_scale(), g.response);
  EXPECT_EQ(b.controller().feedforward_compliance_scale(), g.compliance);
  EXPECT_GT(g.response, 1.005);
  EXPECT_NEAR(g.compliance, 1.0 + 5e-4 * (estimated - 25.0), 1e-3);
}

// With the key false (the default) the same drift is estimated but the inverse stays the
// identified one; without adaptation there is nothing adapted to feed.
TEST(LoopFeedforward, TheKeyFalseOrNoAdaptationKeepsTheIdentifiedFeedforward) {
  EXPECT_FALSE(LoopConfig{}.adaptation_feedforward_estimate);
  WarmingBench b({.feedforward_estimate = false});
  arm(b);
  b.play(4.0);
  EXPECT_GT(b.adapted->drift().temperature_degc, 35.0);
  EXPECT_GT(b.adapted->feedforward_scales().response, 1.005);
  EXPECT_EQ(b.controller().feedforward_response_scale(), 1.0);
  EXPECT_EQ(b.controller().feedforward_compliance_scale(), 1.0);
  WarmingBench plain({.adapt = false});
  arm(plain);
  plain.play(4.0);
  EXPECT_EQ(plain.controller().feedforward_response_scale(), 1.0);
  EXPECT_EQ(plain.controller().feedforward_compliance_scale(), 1.0);
}

// A measured temperature with the model's fitted coefficients reaches the feedforward with the
// key false too (as before the key): at 45 degC the compliance scale is 1 + 5e-4 x 20 K.
TEST(LoopFeedforward, AMeasuredTemperatureReachesTheFeedforwardWithTheKeyFalse) {
  WarmingBench b({.feedforward_estimate = false, .measured = true});
  arm(b);
  b.play(4.0);
  EXPECT_NEAR(b.controller().feedforward_compliance_scale(), 1.01, 1e-9);
  EXPECT_EQ(b.controller().feedforward_response_scale(), b.adapted->feedforward_scales().response);
  EXPECT_GT(b.controller().feedforward_response_scale(), 1.005);
}

// Frozen (`ctl adapt freeze`), the scales stay at the frozen drift while the stack warms on:
// the compliance scale, a function of the drift alone, does not move; resumed, it follows.
TEST(LoopFeedforward, FrozenTheFeedforwardKeepsTheFrozenDrift) {
  WarmingBench b({.ramp_s = 6.0});
  arm(b);
  b.play(2.0);
  ASSERT_EQ(b.send({0, CommandKind::kAdapt, 1.0}), CommandResult::kDone);
  const double frozen = b.controller().feedforward_compliance_scale();
  EXPECT_GT(frozen, 1.0);
  b.play(3.0);  // the plant warms by about 10 K meanwhile
  EXPECT_EQ(b.controller().feedforward_compliance_scale(), frozen);
  EXPECT_EQ(b.controller().feedforward_compliance_scale(),
            b.adapted->feedforward_scales().compliance);
  ASSERT_EQ(b.send({0, CommandKind::kAdapt, 0.0}), CommandResult::kDone);
  b.play(3.0);
  EXPECT_GT(b.controller().feedforward_compliance_scale(), frozen + 2e-3);
}

// Why the key is off by default: in open loop on this bench (the feedforward's stress is the
// one at arm, so the load spring leaves the stroke short by about a third of the sine's range)
// the warming lengthens the stroke and so lowers the error; the estimate's scales take back
// most of that lengthening, as they should, and the error grows. 2 s of the sine after the
// warming (at 45 degC, or at 25 degC throughout).
TEST(LoopFeedforward, TheEstimateTakesTheWarmingOutOfTheOpenLoopButItsErrorGrows) {
  const auto run = [](const BenchSetup& setup) {
    WarmingBench b(setup);
    arm(b);
    b.play(4.0);
    return b.play(2.0);
  };
  const WarmingBench::Error cold = run({.feedforward_estimate = false, .end_degc = 25.0});
  const WarmingBench::Error identified = run({.feedforward_estimate = false});
  const WarmingBench::Error estimate = run({});
  std::printf(
      "open loop, true S - setpoint, %% of the sine's range: RMS (mean) at 25 degC %.2f (%.2f); "
      "at 45 degC identified %.2f (%.2f), with the estimate %.2f (%.2f); the estimate takes back "
      "%.0f %% of the warming's change of the mean\n",
      100 * cold.rms / kSineRange, 100 * cold.mean / kSineRange, 100 * identified.rms / kSineRange,
      100 * identified.mean / kSineRange, 100 * estimate.rms / kSineRange,
      100 * estimate.mean / kSineRange,
      100 * (identified.mean - estimate.mean) / (identified.mean - cold.mean));
  // Measured: 35.1 % (-34.5 %) at 25 degC; 32.9 % (-32.4 %) identified, 34.2 % (-33.7 %) with
  // the estimate at 45 degC; 60 % of the warming's change taken back.
  EXPECT_LT(cold.mean, -0.3 * kSineRange);  // the spring's short stroke
  EXPECT_GT(identified.mean - cold.mean, 0.015 * kSineRange);
  const double taken_back = (identified.mean - estimate.mean) / (identified.mean - cold.mean);
  EXPECT_GT(taken_back, 0.45);
  EXPECT_LT(taken_back, 1.0);
  EXPECT_GT(estimate.rms, identified.rms + 0.008 * kSineRange);
}

}  // namespace
}  // namespace selfsense::runtime
