// The health estimator and its alarms on synthetic signals whose capacitance, loop area and
// leakage are known in closed form: D = C E + B y + sigma integral(E dt), y a play operator
// of threshold r on E (zero slope after a reversal, like a Preisach loop; its loop area is
// 2 r (E_max - E_min - 2 r)). Each figure is asserted within a stated tolerance.
#include "selfsense/adaptation/health_estimator.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "selfsense/adaptation/health_alarms.hpp"
#include "selfsense/adaptation/trend_filter.hpp"
#include "support/allocation_counter.hpp"

namespace selfsense::adaptation {
namespace {

static_assert(noexcept(std::declval<HealthEstimator&>().step(0.0, 0.0, true)));
static_assert(noexcept(std::declval<HealthEstimator&>().step(0.0, 0.0, 0.0, true)));

constexpr double kTs = 1e-4;
constexpr double kC = 2.0e-8;    // [F/m]
constexpr double kB = 5.0e-9;    // the loop's weight [F/m]
constexpr double kR = 2.0e5;     // play threshold [V/m]
constexpr double kEmax = 2.0e6;  // the drive: 0 .. 2 MV/m at 5 Hz
constexpr double kHz = 5.0;

// The synthetic stack: capacitance and loop scales may change while it runs.
struct Synthetic {
  double c_scale{1.0};
  double loop_scale{1.0};
  double sigma{0.0};  // leakage conductivity [S/m]
  double play{0.0};
  double leak{0.0};
  double noise{0.0};  // D noise [C/m^2]
  std::mt19937_64 rng{3};
  std::normal_distribution<double> n01{};
  double d(double e) {
    play = std::max(e - kR, std::min(e + kR, play));
    leak += sigma * e * kTs;
    return kC * c_scale * e + kB * loop_scale * play + leak + noise * n01(rng);
  }
};

// Synthetic signals have no creep to settle: 1 s before the baseline, not 100 s.
HealthEstimatorConfig quick() {
  HealthEstimatorConfig c;
  c.settle_s = 1.0;
  return c;
}

double drive(double t) {
  return 0.5 * kEmax * (1.0 - std::cos(2.0 * std::numbers::pi * kHz * t));
}

void run(HealthEstimator& h, Synthetic& s, double& t, double seconds) {
  const auto n = static_cast<long>(seconds / kTs);
  for (long k = 0; k < n; ++k) {
    t += kTs;
    const double e = drive(t);
    h.step(e, s.d(e), true);
  }
}

TEST(HealthEstimator, CapacitanceAndLoopAreaOfAKnownLoop) {
  HealthEstimator h(quick(), kTs);
  Synthetic s;
  double t = 0.0;
  run(h, s, t, 10.0);
  const HealthFigures f = h.figures();
  ASSERT_TRUE(f.has_capacitance && f.has_dissipation);
  EXPECT_NEAR(f.capacitance_f_per_m, kC, 1e-3 * kC);    // 0.1 %
  const double w = kB * 2.0 * kR * (kEmax - 2.0 * kR);  // 3200 J/m^3
  EXPECT_NEAR(f.dissipation_j_per_m3, w, 5e-3 * w);     // 0.5 %
  EXPECT_GE(f.cycles, 48U);                             // 50 cycles, the first not whole
  EXPECT_TRUE(f.baseline_ready);
  ASSERT_TRUE(f.has_depolarisation);
  EXPECT_NEAR(f.depolarisation, 0.0, 1e-3);
}

TEST(HealthEstimator, LossOfPolarisationIsToldFromWarming) {
  HealthEstimatorConfig config = quick();  // capacitance +0.4 %/K, loop -0.4 %/K
  HealthEstimator h(config, kTs);
  Synthetic s;
  s.noise = 2e-6;
  double t = 0.0;
  run(h, s, t, 10.0);
  // Warmer by 10 K: capacitance +4 %, loop -4 %. No loss of polarisation.
  s.c_scale = 1.04;
  s.loop_scale = 0.96;
  run(h, s, t, 120.0);
  EXPECT_NEAR(h.figures().depolarisation, 0.0, 2e-3);  // 0.2 % of polarisation
  // And now 5 % of the polarisation lost as well.
  s.loop_scale = 0.96 * 0.95;
  run(h, s, t, 120.0);
  EXPECT_NEAR(h.figures().depolarisation, 0.05, 2e-3);
  // A sensitivity of 0.5: the same change of the loop is twice the loss.
  config.depolarisation_sensitivity = 0.5;
  HealthEstimator half(config, kTs);
  Synthetic aged;
  double t1 = 0.0;
  run(half, aged, t1, 10.0);
  aged.loop_scale = 0.95;
  run(half, aged, t1, 120.0);
  EXPECT_NEAR(half.figures().depolarisation, 0.10, 2e-3);
  config.depolarisation_sensitivity = 1.0;
  // Warming read as a loss (no compensation): the loop's 4 % alone.
  config.dissipation_per_k = 0.0;
  HealthEstimator plain(config, kTs);
  Synthetic cold;
  double t2 = 0.0;
  run(plain, cold, t2, 10.0);
  cold.c_scale = 1.04;
  cold.loop_scale = 0.96;
  run(plain, cold, t2, 120.0);
  EXPECT_NEAR(plain.figures().depolarisation, 0.04, 2e-3);
}

TEST(HealthEstimator, ALossOfFivePercentPerHourHasItsSlope) {
  HealthEstimatorConfig config = quick();
  config.trend_time_s = 10.0;
  config.slope_time_s = 120.0;
  HealthEstimator h(config, kTs);
  Synthetic s;
  double t = 0.0;
  run(h, s, t, 10.0);
  const double start = t;
  while (t < start + 600.0) {
    s.loop_scale = 1.0 - 0.05 * (t - start) / 3600.0;
    run(h, s, t, 1.0);
  }
  const HealthFigures f = h.figures();
  EXPECT_NEAR(f.depolarisation_per_h, 0.05, 0.005);  // 10 %
  // The slow value lags the ramp by rate * tau1.
  const double truth = 0.05 * 600.0 / 3600.0;
  EXPECT_NEAR(f.depolarisation, truth - 0.05 / 3600.0 * config.trend_time_s, 5e-4);
}

TEST(HealthEstimator, ADriveOfOtherExtremesIsNotComparedWithTheBaseline) {
  HealthEstimator h(quick(), kTs);
  Synthetic s;
  double t = 0.0;
  run(h, s, t, 10.0);
  // Half the amplitude: measured, not compared (after the cycle that ends at the change).
  std::uint64_t compared = 0;
  for (long k = 0; k < 100000; ++k) {
    t += kTs;
    const double e = 0.5 * drive(t);
    h.step(e, s.d(e), true);
    if (k == 1000) compared = h.figures().compared_cycles;
  }
  EXPECT_GT(h.figures().cycles, 90U);
  EXPECT_EQ(h.figures().compared_cycles, compared);
}

// With the model's predicted D for the same field path (here the stack as new: the same
// capacitance and a play of the same threshold at loop scale 1), a cycle of other extremes is
// compared: the drive raised by 10 % after a 5 % loss, as a position loop makes up the stroke.
TEST(HealthEstimator, AgainstTheModelsLoopADriveOfOtherExtremesIsCompared) {
  for (const bool model_reference : {true, false}) {
    HealthEstimatorConfig c = quick();
    c.model_reference = model_reference;
    HealthEstimator h(c, kTs);
    Synthetic s;
    Synthetic model;
    double t = 0.0;
    const auto run_with = [&](double amplitude, double seconds) {
      const auto n = static_cast<long>(seconds / kTs);
      for (long k = 0; k < n; ++k) {
        t += kTs;
        const double e = amplitude * drive(t);
        const double d = s.d(e);
        h.step(e, d, model.d(e), true);
      }
    };
    run_with(1.0, 10.0);
    ASSERT_TRUE(h.figures().baseline_ready);
    const std::uint64_t compared = h.figures().compared_cycles;
    s.loop_scale = 0.95;
    run_with(1.1, 200.0);  // ten trend times
    const HealthFigures f = h.figures();
    if (model_reference) {
      EXPECT_GT(f.compared_cycles, compared + 900U);
      EXPECT_NEAR(f.depolarisation, 0.05, 1e-3);  // 5 % within 0.1 % of polarisation
    } else {
      // The span moved by 10 %: not compared (but the cycle that ends at the change).
      EXPECT_LE(f.compared_cycles, compared + 1U);
    }
  }
}

TEST(HealthEstimator, LeakageResistivityFromAHold) {
  HealthEstimator h(quick(), kTs);
  Synthetic s;
  s.sigma = 1.0e-10;  // rho = 1e10 Ohm m
  s.noise = 2e-6;
  double t = 0.0;
  run(h, s, t, 1.0);
  for (long k = 0; k < 600000; ++k) {  // 60 s at 1.5 MV/m
    t += kTs;
    h.step(1.5e6, s.d(1.5e6), true);
  }
  const HealthFigures f = h.figures();
  ASSERT_TRUE(f.has_leakage);
  EXPECT_GE(f.holds, 10U);
  EXPECT_NEAR(f.leakage_resistivity_ohm_m, 1e10, 0.02e10);  // 2 %
}

TEST(HealthEstimator, ARejectedSampleEndsTheCycleInProgress) {
  HealthEstimator h(quick(), kTs);
  Synthetic s;
  double t = 0.0;
  run(h, s, t, 1.0);
  // A rejection at every cycle's top: no cycle completes after the first.
  std::uint64_t before = 0;
  for (long k = 0; k < 20000; ++k) {
    t += kTs;
    const double e = drive(t);
    h.step(e, s.d(e), k % 2000 != 1000);
    if (k == 1000) before = h.figures().cycles;
  }
  EXPECT_EQ(h.figures().cycles, before);
}

TEST(HealthEstimator, StateRoundTripsAndStepsDoNotAllocate) {
  HealthEstimator h(quick(), kTs);
  Synthetic s;
  s.sigma = 1e-10;
  double t = 0.0;
  std::vector<double> state(HealthEstimator::state_size());
  {
    test::AllocationCounter counter;
    run(h, s, t, 10.0);
    h.save_state(state);
    const HealthFigures f = h.figures();
    static_cast<void>(f);
    EXPECT_EQ(counter.count(), 0U);
    EXPECT_EQ(counter.locks(), 0U);
  }
  HealthEstimator restored(quick(), kTs);
  restored.restore_state(state);
  const HealthFigures a = h.figures();
  const HealthFigures b = restored.figures();
  EXPECT_EQ(a.capacitance_f_per_m, b.capacitance_f_per_m);
  EXPECT_EQ(a.dissipation_j_per_m3, b.dissipation_j_per_m3);
  EXPECT_EQ(a.depolarisation, b.depolarisation);
  EXPECT_EQ(a.cycles, b.cycles);
  EXPECT_TRUE(b.baseline_ready);
  EXPECT_EQ(h.time_s(), restored.time_s());
}

TEST(HealthEstimator, TheConfigurationNamesTheViolatedKey) {
  HealthEstimatorConfig c;
  std::string why;
  EXPECT_TRUE(c.is_valid("health.", &why));
  c.slope_time_s = 5.0;
  EXPECT_FALSE(c.is_valid("health.", &why));
  EXPECT_EQ(why, "health.slope_time_s: must be > trend_time_s");
  c = {};
  c.capacitance_per_k = 0.0;
  EXPECT_FALSE(c.is_valid("health.", &why));
  EXPECT_EQ(why, "health.capacitance_per_k: must be finite and not 0");
  c = {};
  c.depolarisation_sensitivity = 0.0;
  EXPECT_FALSE(c.is_valid("health.", &why));
  EXPECT_EQ(why, "health.depolarisation_sensitivity: must be in (0, 2]");
  c = {};
  c.max_span_change = 0.0;
  EXPECT_FALSE(c.is_valid("health.", &why));
  EXPECT_EQ(why, "health.max_span_change: must be in (0, 1]");
  c = {};
  c.reversal_field_v_per_m = -1.0;
  EXPECT_THROW(HealthEstimator(c, kTs), std::invalid_argument);
  HealthBands bands;
  bands.max_depolarisation_pct = 0.0;
  EXPECT_FALSE(bands.is_valid("health.", &why));
  EXPECT_EQ(why, "health.max_depolarisation_pct: 0 must be within (0, 100)");
  bands = {};
  bands.max_temperature_degc = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(bands.is_valid("health.", &why));
  EXPECT_EQ(why, "health.max_temperature_degc: nan must be finite");
  bands = {};
  bands.min_leakage_resistivity_ohm_m = -1.0;
  EXPECT_FALSE(bands.is_valid("health.", &why));
  EXPECT_EQ(why, "health.min_leakage_resistivity_ohm_m: -1 must be > 0");
}

TEST(TrendFilter, ARampHasItsSlopeAndTheValueLagsByTau1) {
  TrendFilter f(10.0, 100.0);
  for (int k = 0; k <= 2000; ++k)
    f.update(3.0 + 0.01 * k * 0.5, k * 0.5);  // 0.01 per s, a value every 0.5 s
  EXPECT_NEAR(f.slope(), 0.01, 1e-5);
  // Lag r tau1 (0.1), less a little for the measurements' spacing (0.0975 at 0.5 s).
  EXPECT_NEAR(f.value(), 3.0 + 0.01 * 1000.0 - 0.01 * 10.0, 5e-3);
}

TEST(HealthAlarms, LatchedUntilResetWhileBackInsideTheBand) {
  HealthAlarms alarms(HealthBands{});
  HealthFigures f;
  f.has_depolarisation = true;
  f.depolarisation = 0.02;
  f.has_leakage = true;
  f.leakage_resistivity_ohm_m = 1e11;
  EXPECT_EQ(alarms.evaluate(f, true, 60.0, 1.0), 0U);
  f.depolarisation = 0.031;
  EXPECT_EQ(alarms.evaluate(f, true, 81.0, 2.0),
            bit(HealthAlarm::kDepolarisation) | bit(HealthAlarm::kOverheating));
  EXPECT_EQ(alarms.raised_at_s(HealthAlarm::kDepolarisation), 2.0);
  f.leakage_resistivity_ohm_m = 5e8;
  EXPECT_EQ(alarms.evaluate(f, false, 81.0, 3.0),
            bit(HealthAlarm::kDepolarisation) | bit(HealthAlarm::kInsulation));
  EXPECT_EQ(alarms.latched(), 7U);
  EXPECT_EQ(alarms.raised_at_s(HealthAlarm::kDepolarisation), 2.0);  // the first time
  // Reset: the overheating is gone (no temperature now), the others are still beyond.
  EXPECT_EQ(alarms.reset(), bit(HealthAlarm::kDepolarisation) | bit(HealthAlarm::kInsulation));
  EXPECT_LT(alarms.raised_at_s(HealthAlarm::kOverheating), 0.0);
  f.depolarisation = 0.0;
  f.leakage_resistivity_ohm_m = 1e11;
  EXPECT_EQ(alarms.evaluate(f, true, 25.0, 4.0), 0U);
  EXPECT_EQ(alarms.latched(), bit(HealthAlarm::kDepolarisation) | bit(HealthAlarm::kInsulation));
  EXPECT_EQ(alarms.reset(), 0U);
  EXPECT_EQ(to_string(HealthAlarm::kInsulation), "insulation");
}

}  // namespace
}  // namespace selfsense::adaptation
