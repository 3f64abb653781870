// The thermal model that carries the drift estimate through holds (thermal_model.hpp): the power
// of a known loop, the exact first-order law, the bounds and the saved state; and, on synthetic
// data whose stack warms with the power it takes and cools on a hold, the adapted reconstruction
// that follows the cooling with it and holds the hot estimate without it.
#include "selfsense/adaptation/thermal_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "selfsense/adaptation/adapted_reconstruction.hpp"
#include "support/allocation_counter.hpp"
#include "support/transducer_data.hpp"

namespace selfsense::adaptation {
namespace {

constexpr double kTs = 1e-4;

TEST(ThermalModelConfig, NamesTheViolatedKey) {
  std::string why;
  ThermalModelConfig c{};
  EXPECT_TRUE(c.is_valid("adaptation.", &why)) << why;
  c.time_constant_s = 0.0;
  EXPECT_FALSE(c.is_valid("adaptation.", &why));
  EXPECT_EQ(why, "adaptation.thermal_time_constant_s: 0 must be > 0");
  EXPECT_THROW(ThermalModel(c, kTs), std::invalid_argument);
  c = ThermalModelConfig{};
  c.resistance_k_per_w = -1.0;
  EXPECT_FALSE(c.is_valid("adaptation.", &why));
  EXPECT_EQ(why, "adaptation.thermal_resistance_k_per_w: -1 must be >= 0");
  c = ThermalModelConfig{};
  c.ambient_degc = std::nan("");
  EXPECT_FALSE(c.is_valid("adaptation.", &why));
  EXPECT_EQ(why, "adaptation.ambient_degc: nan must be finite");
  // Checked with the estimator's configuration only when enabled.
  DriftEstimatorConfig d{};
  d.thermal.stack_volume_m3 = 0.0;
  EXPECT_TRUE(d.is_valid("adaptation.", &why));
  d.thermal.enabled = true;
  EXPECT_FALSE(d.is_valid("adaptation.", &why));
  EXPECT_EQ(why, "adaptation.stack_volume_m3: 0 must be > 0");
  EXPECT_THROW(ThermalModel(ThermalModelConfig{}, 0.0), std::invalid_argument);
}

// A lossy linear dielectric, D = eps E0 sin(w t - delta): the power over whole cycles is the
// ellipse's area times the frequency times the volume, pi eps E0^2 sin(delta) f V; a lossless
// one (delta 0) takes none over a cycle.
TEST(ThermalModel, ThePowerIsTheLoopAreaTimesTheFrequency) {
  for (const double delta : {0.0, 0.05}) {
    ThermalModelConfig c{};
    c.stack_volume_m3 = 2.5e-7;
    ThermalModel m(c, kTs);
    const double eps = 2e-8;
    const double e0 = 1e6;
    const double f = 100.0;
    const int n = 10000;  // 100 cycles
    double sum = 0.0;
    for (int k = 0; k <= n; ++k) {
      const double wt = 2 * std::numbers::pi * f * k * kTs;
      m.step(e0 * std::sin(wt), eps * e0 * std::sin(wt - delta), true);
      if (k > 0) sum += m.power_w();
    }
    const double expected = std::numbers::pi * eps * e0 * e0 * std::sin(delta) * f * 2.5e-7;
    EXPECT_NEAR(sum / n, expected, 1e-3 * std::abs(expected) + 1e-9) << "delta " << delta;
  }
}

// The exact discretisation: a constant power settles at theta_amb + R_th P, 63.2 % of the way
// after tau; without power the temperature decays to the ambient by exp(-t / tau).
TEST(ThermalModel, FollowsTheFirstOrderLawExactly) {
  ThermalModelConfig c{};
  c.resistance_k_per_w = 200.0;
  c.time_constant_s = 20.0;
  c.ambient_degc = 25.0;
  c.stack_volume_m3 = 1e-6;
  ThermalModel m(c, kTs);
  // P = V E dD/dt: E = 1e6 V/m and D rising 0.1 C/m^2 per s take 0.1 W.
  m.step(1e6, 0.0, true);  // the first sample: no increment yet
  double theta = 25.0;
  const int per_tau = static_cast<int>(std::lround(20.0 / kTs));
  for (int k = 0; k < per_tau; ++k) {
    m.step(1e6, 0.1 * (k + 1) * kTs, true);
    theta = m.predict(theta);
  }
  EXPECT_NEAR(m.power_w(), 0.1, 1e-9);
  EXPECT_NEAR(theta, 25.0 + 20.0 * (1.0 - std::exp(-1.0)), 1e-6);
  // Rejected samples bring no power, and cooling follows exp(-t / tau).
  const double hot = theta;
  m.step(1e6, 1e3, false);
  EXPECT_EQ(m.power_w(), 0.0);
  for (int k = 0; k < per_tau; ++k) {
    m.step(1e6, 0.5, true);  // a hold: no power
    theta = m.predict(theta);
  }
  EXPECT_NEAR(theta, 25.0 + (hot - 25.0) * std::exp(-1.0), 1e-6);
  // Bounded power; state round trip.
  m.step(1e6, 1e9, true);
  EXPECT_EQ(m.power_w(), c.max_power_w);
  std::vector<double> state(ThermalModel::state_size());
  m.save_state(state);
  ThermalModel other(c, kTs);
  other.restore_state(state);
  EXPECT_EQ(other.predict(30.0), m.predict(30.0));
}

// A stack that warms with the power it takes (the same law with R_th, tau_th, V) under a
// sine, then holds its field while it cools, then moves again. E, D measured with noise; the
// true temperature, stress and the data's drift per sample.
struct Heated {
  models::TransducerModel model;
  std::vector<double> e, d, t, theta;
  std::size_t hold_from{0}, hold_to{0};
};

constexpr double kPermPerK = 4.0e-3;
constexpr double kLoopPerK = -4.0e-3;
constexpr double kCouplingPerK = 2.0e-3;
constexpr double kVolume = 1e-6;

Heated heated(double r_th, double tau_s, std::uint64_t seed) {
  Heated out{test::typical_transducer(kTs), {}, {}, {}, {}};
  const models::SideModel& sensor = *out.model.sensor;
  models::SideOperator truth(sensor);
  const SideSplit split(truth);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  const std::size_t warm = 100000;  // 10 s of a 20 Hz sine
  const std::size_t hold = 100000;  // 10 s at 1 MV/m
  const std::size_t again = 10000;  // 1 s of the sine
  out.hold_from = warm;
  out.hold_to = warm + hold;
  const double a = std::exp(-kTs / tau_s);
  double theta = 25.0;
  double last_e = 0.0;
  double last_d = 0.0;
  double lo = 1e300;
  double hi = -1e300;
  for (std::size_t k = 0; k < warm + hold + again; ++k) {
    const double time = static_cast<double>(k) * kTs;
    const bool holding = k >= out.hold_from && k < out.hold_to;
    const double e =
        holding ? 1e6 : 1e6 * (1.0 + 0.9 * std::sin(2 * std::numbers::pi * 20.0 * time));
    const double t = -1e7 * (1.0 + 0.5 * std::sin(2 * std::numbers::pi * 0.2 * time + 0.5));
    const double rise = theta - 25.0;
    const SideSplit::Parts parts = split.split(truth, e, truth.step_unloaded(e) - sensor.offset);
    const double d = sensor.offset + (1.0 + kLoopPerK * rise) * parts.loop +
                     (1.0 + kPermPerK * rise) * parts.linear +
                     (1.0 + kCouplingPerK * rise) * truth.coupling() * t;
    out.theta.push_back(theta);
    out.e.push_back(e + 100.0 * n01(rng));
    out.d.push_back(d + 2e-6 * n01(rng));
    out.t.push_back(t);
    if (k > 0) {
      const double power = kVolume * 0.5 * (e + last_e) * (d - last_d) / kTs;
      theta = 25.0 + a * (theta - 25.0) + (1.0 - a) * r_th * power;
    }
    last_e = e;
    last_d = d;
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  out.model.drive_range = models::InputRange{0.0, 2e6};
  out.model.sensed_range = models::InputRange{lo, hi};
  return out;
}

struct Followed {
  double temperature_error_end_of_hold{0.0};  // |theta_eq - theta| at the hold's end [K]
  double stress_rms_hold{0.0};                // RMS(T_hat - T) over the hold [Pa]
  double temperature_rms{0.0};                // RMS(theta_eq - theta) after the first 2 s [K]
};

constexpr double kRth = 100.0;
constexpr double kTau = 5.0;

Followed follow(const Heated& data, bool thermal, double r_th, double tau_s) {
  DriftEstimatorConfig config{};
  config.thermal.enabled = thermal;
  config.thermal.resistance_k_per_w = r_th;
  config.thermal.time_constant_s = tau_s;
  config.thermal.ambient_degc = 25.0;
  config.thermal.stack_volume_m3 = kVolume;
  AdaptedReconstruction rec(data.model, config);
  Followed f{};
  double sum_t = 0.0;
  double sum_theta = 0.0;
  std::size_t n_theta = 0;
  for (std::size_t k = 0; k < data.e.size(); ++k) {
    const AdaptedReconstruction::Estimate out = rec.step(data.e[k], data.d[k]);
    const double theta_eq = rec.drift().temperature_degc;
    if (k >= data.hold_from && k < data.hold_to) {
      sum_t += (out.stress - data.t[k]) * (out.stress - data.t[k]);
    }
    if (k + 1 == data.hold_to) f.temperature_error_end_of_hold = std::abs(theta_eq - data.theta[k]);
    if (k >= 20000) {
      sum_theta += (theta_eq - data.theta[k]) * (theta_eq - data.theta[k]);
      ++n_theta;
    }
  }
  f.stress_rms_hold = std::sqrt(sum_t / static_cast<double>(data.hold_to - data.hold_from));
  f.temperature_rms = std::sqrt(sum_theta / static_cast<double>(n_theta));
  std::printf(
      "thermal %d (R_th %.0f K/W, tau %.1f s): end of hold %.3f K off, temperature RMS %.3f K, "
      "T_hat RMS on the hold %.4g Pa\n",
      thermal ? 1 : 0, r_th, tau_s, f.temperature_error_end_of_hold, f.temperature_rms,
      f.stress_rms_hold);
  return f;
}

// The stack warms by about 20 K under the sine and cools by most of it during the 10 s hold.
// Without the thermal model the estimator, gated on excitation, holds the hot estimate through
// the hold; with it the estimate cools with the stack.
TEST(AdaptedReconstruction, TheThermalModelCarriesTheEstimateThroughAHold) {
  const Heated data = heated(kRth, kTau, 11);
  const double peak = data.theta[data.hold_from];
  const double cooled = data.theta[data.hold_to - 1];
  std::printf("the stack: %.2f degC at the hold's start, %.2f degC at its end\n", peak, cooled);
  ASSERT_GT(peak - 25.0, 15.0);
  ASSERT_GT(peak - cooled, 10.0);
  const Followed without = follow(data, false, kRth, kTau);
  const Followed with = follow(data, true, kRth, kTau);
  EXPECT_GT(without.temperature_error_end_of_hold, 10.0);
  EXPECT_LT(with.temperature_error_end_of_hold, 1.0);
  EXPECT_LT(with.stress_rms_hold, 0.2 * without.stress_rms_hold);
  EXPECT_LT(with.temperature_rms, 0.3 * without.temperature_rms);
}

// The datasheet's values off by half again (R_th and tau_th 1.5x): the excitation corrects the
// estimate, the hold's cooling is followed at the wrong pace, still far better than holding.
TEST(AdaptedReconstruction, TheThermalModelToleratesWrongDatasheetValues) {
  const Heated data = heated(kRth, kTau, 12);
  const Followed without = follow(data, false, kRth, kTau);
  const Followed off = follow(data, true, 1.5 * kRth, 1.5 * kTau);
  const Followed off_low = follow(data, true, kRth / 1.5, kTau / 1.5);
  EXPECT_LT(off.temperature_error_end_of_hold, 0.5 * without.temperature_error_end_of_hold);
  EXPECT_LT(off_low.temperature_error_end_of_hold, 0.5 * without.temperature_error_end_of_hold);
}

// Frozen, the estimate holds even with the thermal model on; the state (with the thermal
// model's) round-trips, and its size grows by the thermal model's only when it is on.
TEST(AdaptedReconstruction, TheThermalModelHoldsWhenFrozenAndSavesItsState) {
  const Heated data = heated(kRth, kTau, 13);
  DriftEstimatorConfig config{};
  config.thermal.enabled = true;
  config.thermal.resistance_k_per_w = kRth;
  config.thermal.time_constant_s = kTau;
  config.thermal.stack_volume_m3 = kVolume;
  AdaptedReconstruction rec(data.model, config);
  AdaptedReconstruction plain(data.model, DriftEstimatorConfig{});
  EXPECT_EQ(rec.state_size(), plain.state_size() + ThermalModel::state_size());
  for (std::size_t k = 0; k < data.hold_from; ++k)
    rec.step(data.e[k], data.d[k]);
  std::vector<double> state(rec.state_size());
  ASSERT_TRUE(rec.save_state(state));
  AdaptedReconstruction resumed(data.model, config);
  ASSERT_TRUE(resumed.restore_state(state));
  rec.set_frozen(true);
  const double hot = rec.drift().temperature_degc;
  for (std::size_t k = data.hold_from; k < data.hold_to; ++k) {
    rec.step(data.e[k], data.d[k]);
    const double a = resumed.step(data.e[k], data.d[k]).stress;
    static_cast<void>(a);
  }
  EXPECT_EQ(rec.drift().temperature_degc, hot);
  EXPECT_LT(resumed.drift().temperature_degc, hot - 10.0);
}

// The step with the thermal model on allocates nothing and takes no lock.
TEST(AdaptationRealTime, TheThermalModelDoesNotAllocateOrLock) {
  const Heated data = heated(kRth, kTau, 14);
  DriftEstimatorConfig config{};
  config.thermal.enabled = true;
  AdaptedReconstruction rec(data.model, config);
  std::vector<double> state(rec.state_size());
  ThermalModel alone(config.thermal, kTs);
  double sink = 0.0;
  test::AllocationCounter counter;
  for (std::size_t k = 0; k < 20000; ++k) {
    sink += rec.step(data.e[k], data.d[k]).stress;
    rec.save_state(state);
    rec.restore_state(state);
    alone.step(data.e[k], data.d[k], k % 7 != 0);
    sink += alone.predict(30.0);
  }
  EXPECT_EQ(counter.count(), 0U);
  EXPECT_EQ(counter.locks(), 0U);
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
}  // namespace selfsense::adaptation
