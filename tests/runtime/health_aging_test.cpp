// Issue 24's aging proof: the loop (runtime::Loop) with the adapted reconstruction and the health
// estimate on the simulated transducer (the daemon's bench, config/plant/daemon.yaml), driven
// open loop by a sine for an hour of simulated time, deterministic (the plant's seed, no clock):
//   - a stack that loses 5 % of its polarisation over the hour (plant.aging) raises the
//     depolarisation alarm (band 3 %) within 60 s of the true loss crossing 3 %;
//   - a stack that does not age, while its temperature ramps and swings, raises no alarm.
//
// Honest differences from the daemon's bench, for CI time (each hour runs in about 10-20 s):
// the loop and the plant run at 1 kHz, not 10 and 20 kHz, so the mount's resonance (2 kHz) is
// left out (mechanics off: the load spring acts quasi-statically) and the model
// (config/models/sim.yaml, identified at 20 kHz) runs at 1 kHz. The aging is the real rate
// (5 %/h), not accelerated. Open loop; the same aging under closed position control is
// health_position_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "health_bench.hpp"
#include "selfsense/adaptation/health_alarms.hpp"
#include "selfsense/control/wave_generator.hpp"
#include "selfsense/drivers/sim/simulated_transducer.hpp"
#include "selfsense/runtime/loop.hpp"

namespace selfsense::runtime {
namespace {

constexpr double kTs = test::kHealthTs;
constexpr double kHour = 3600.0;
constexpr double kBandPct = 3.0;
constexpr double kStart = 120.0;  // the stack as new: the health estimate's settling and baseline

struct HourRun {
  double raised_at_s{-1.0};        // the depolarisation alarm; < 0: never
  std::uint32_t latched{0};        // every alarm latched at the end
  double max_depolarisation{0.0};  // largest |estimate| seen [1]
  double final_depolarisation{0.0};
  double max_temperature_degc{0.0};  // largest equivalent temperature seen
  std::uint64_t compared_cycles{0};
  std::uint32_t faults{0};
};

HourRun run_hour(double polarisation_loss_per_h, const drivers::TemperatureRamp& temperature,
                 double seconds = kStart + kHour) {
  drivers::SimulatedTransducer driver(test::health_plant(polarisation_loss_per_h, kStart),
                                      temperature);
  std::string why;
  EXPECT_TRUE(driver.configure({kTs}, &why)) << why;
  EXPECT_TRUE(driver.activate(&why)) << why;

  // The coefficients were measured on this bench (DISABLED_Calibration, at constant temperatures
  // and a faster aging, not the runs below): the reversal capacitance +0.403 %/K, the loop area
  // -0.378 %/K, and the compensated loop's change per loss 0.76 (the load spring's share of the
  // reversal slope).
  LoopConfig lc = test::health_loop_config();
  lc.health_bands.max_depolarisation_pct = kBandPct;
  lc.health_bands.max_temperature_degc = 80.0;
  ControllerConfig cc;
  cc.mode = ControlMode::kOpenLoop;
  const std::unique_ptr<Loop> bench = test::health_loop(lc, driver, cc);
  Loop& loop = *bench;

  const control::WaveGenerator::Config wc = test::strain_sine();  // 1e-4 .. 1.1e-3 at 2 Hz
  std::uint64_t id = 0;
  const auto send = [&](LoopCommand c) {
    c.id = ++id;
    EXPECT_TRUE(loop.submit(c));
    loop.cycle(false);
  };
  loop.cycle(false);
  send({0, CommandKind::kReset});
  send({0, CommandKind::kArm});
  send({0, CommandKind::kWave, 0.0, ControlMode::kOpenLoop,
        std::make_unique<control::WaveGenerator>(wc, kTs).release()});

  HourRun out;
  const auto cycles = static_cast<long>(seconds / kTs);
  for (long k = 0; k < cycles; ++k) {
    loop.cycle(false);
    if (k % 1000 != 0) continue;
    const StatusSnapshot& s = loop.local_status();
    if (s.health.figures.has_depolarisation) {
      out.max_depolarisation =
          std::max(out.max_depolarisation, std::abs(s.health.figures.depolarisation));
    }
    out.max_temperature_degc = std::max(out.max_temperature_degc, s.adaptation.temperature_degc);
    if (k % 300000 == 0) {
      std::printf("t %6.0f s  depolarisation %6.3f %%  C %.5e  W %.2f  theta_eq %.1f  plant %.1f\n",
                  static_cast<double>(k) * kTs, 100.0 * s.health.figures.depolarisation,
                  s.health.figures.capacitance_f_per_m, s.health.figures.dissipation_j_per_m3,
                  s.adaptation.temperature_degc, driver.temperature_degc());
    }
  }
  const StatusSnapshot& s = loop.local_status();
  out.raised_at_s =
      s.health.raised_at_s[static_cast<std::size_t>(adaptation::HealthAlarm::kDepolarisation)];
  out.latched = s.health.latched;
  out.final_depolarisation = s.health.figures.depolarisation;
  out.compared_cycles = s.health.figures.compared_cycles;
  out.faults = s.faults;
  Retired r;
  while (loop.take_retired(r)) {
    delete r.wave;
    delete r.model;
    delete r.feedforward;
  }
  return out;
}

TEST(HealthAging, DISABLED_Calibration) {
  static_cast<void>(run_hour(0.0, {25.0, 25.0, 0.0, 0.0, 600.0}, 601.0));
  static_cast<void>(run_hour(0.0, {45.0, 45.0, 0.0, 0.0, 600.0}, 601.0));
  static_cast<void>(run_hour(0.6, {25.0, 25.0, 0.0, 0.0, 600.0}, 601.0));
}

TEST(HealthAging, FivePercentLossOfPolarisationPerHourIsFlaggedWithinAMinute) {
  // 30 degC with a swing of +-5 K every 20 minutes.
  const HourRun run = run_hour(0.05, {30.0, 30.0, 0.0, 5.0, 1200.0});
  const double crossing_s = kStart + kBandPct / 100.0 / 0.05 * kHour;  // 2280 s
  std::printf(
      "aging: raised at %.1f s (true crossing %.0f s), final estimate %.3f %% (true 5 %%), "
      "max |estimate| %.3f %%, compared cycles %llu\n",
      run.raised_at_s, crossing_s, 100.0 * run.final_depolarisation, 100.0 * run.max_depolarisation,
      static_cast<unsigned long long>(run.compared_cycles));
  EXPECT_EQ(run.faults, 0U);  // warnings, not faults
  ASSERT_GE(run.raised_at_s, 0.0);
  EXPECT_LE(run.raised_at_s, crossing_s + 60.0);
  EXPECT_GE(run.raised_at_s, crossing_s - 60.0);       // measured 46 s early (2234 s)
  EXPECT_NEAR(run.final_depolarisation, 0.05, 0.005);  // measured 4.99 %
}

TEST(HealthAging, NoAlarmInAnHourOfNormalOperationWithTemperatureSwings) {
  // Up from 25 to 40 degC in ten minutes, then swings of +-8 K every 15 minutes.
  const HourRun run = run_hour(0.0, {25.0, 40.0, 600.0, 8.0, 900.0});
  std::printf(
      "normal: max |estimate| %.3f %%, final %.3f %%, max equivalent temperature %.1f degC, "
      "latched %u, compared cycles %llu\n",
      100.0 * run.max_depolarisation, 100.0 * run.final_depolarisation, run.max_temperature_degc,
      run.latched, static_cast<unsigned long long>(run.compared_cycles));
  EXPECT_EQ(run.latched, 0U);
  EXPECT_EQ(run.faults, 0U);
  EXPECT_GT(run.compared_cycles, 6000U);
  EXPECT_LT(run.max_depolarisation, 0.027);  // measured 2.05 % (the band is 3 %)
}

}  // namespace
}  // namespace selfsense::runtime
