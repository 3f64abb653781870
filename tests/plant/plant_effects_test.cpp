// Each effect is visible where the physics says it should be and absent when switched off.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>
#include <string>
#include <vector>

#include "plant_test_util.hpp"
#include "selfsense/plant/plant.hpp"

namespace selfsense::plant {
namespace {

using test::cosine_cycles;
using test::run_field;
using test::step_field;

double e_of(const StepOutput& o) {
  return o.e_v_per_m;
}
double s_of(const StepOutput& o) {
  return o.s;
}
double d_of(const StepOutput& o) {
  return o.d_c_per_m2;
}

TEST(PlantEffects, CleanStackIsLinearWithRealisticTerminalValues) {
  PlantConfig c{};
  c.material.d33_m_per_v = 7.5e-10;
  const Derived derived = derive(c);
  EXPECT_NEAR(derived.length_m, 10e-3, 0.1e-3);
  EXPECT_GT(derived.capacitance_f, 1e-6);
  EXPECT_LT(derived.capacitance_f, 2e-6);
  EXPECT_NEAR(derived.free_stroke_m, 15e-6, 0.1e-6);
  EXPECT_GT(derived.blocking_force_n, 800.0);
  EXPECT_LT(derived.blocking_force_n, 1300.0);

  const auto out = run_field(c, step_field(10, 10, 2.0e6));
  const StepOutput& o = out.back();
  EXPECT_DOUBLE_EQ(o.u_v, 120.0);
  EXPECT_NEAR(o.s, 7.5e-10 * 2.0e6, 1e-15);
  EXPECT_NEAR(o.d_c_per_m2, 2.0e-8 * 2.0e6, 1e-15);
  EXPECT_NEAR(o.d_meas_c_per_m2, o.d_c_per_m2, 1e-15);
  EXPECT_NEAR(o.q_c, o.d_c_per_m2 * 167 * 25e-6, 1e-15);
  EXPECT_NEAR(o.t_pa, 0.0, 1e-6);
}

TEST(PlantEffects, HysteresisOpensTheLoopOnlyWhenOn) {
  PlantConfig c{};
  c.sample_rate_hz = 10000.0;
  const auto e = cosine_cycles(c.sample_rate_hz, 5.0, 2);
  const std::size_t half = e.size() / 2;
  const auto off = run_field(c, e);
  c.hysteresis.enabled = true;
  const auto on = run_field(c, e);
  const double stroke =
      std::max_element(on.begin(), on.end(), [](auto& a, auto& b) { return a.s < b.s; })->s;
  const double width_on = test::loop_height(on, half, on.size(), 1.0e6, 2e4, e_of, s_of);
  const double width_off = test::loop_height(off, half, off.size(), 1.0e6, 2e4, e_of, s_of);
  EXPECT_GT(width_on / stroke, 0.08);
  EXPECT_LT(width_on / stroke, 0.20);
  EXPECT_NEAR(width_off, 0.0, 1e-12);
  // The polarisation drives D too.
  EXPECT_GT(test::loop_height(on, half, on.size(), 1.0e6, 2e4, e_of, d_of), 1e-3);
}

TEST(PlantEffects, CreepKeepsMovingAfterAStepAndSettles) {
  PlantConfig c{};
  c.sample_rate_hz = 1000.0;
  c.creep.enabled = true;
  c.creep.tau_s = {0.01, 0.1, 1.0, 8.0};
  c.creep.s_weights = {0.01, 0.01, 0.02, 0.02};
  c.creep.d_weights = {0.01, 0.01, 0.01, 0.01};
  const auto e = step_field(10, 100000, 1.0e6);  // 100 s hold
  const auto on = run_field(c, e);
  const double s0 = 5.5e-10 * 1.0e6;
  const auto at = [&on](double t) { return on[10 + static_cast<std::size_t>(t * 1000.0)].s; };
  // Still moving between 0.1 s and 10 s after the step ...
  EXPECT_GT(at(10.0) - at(0.1), 0.02 * s0);
  EXPECT_GT(at(1.0), at(0.1));
  // ... and settled at the instantaneous response times (1 + sum of weights).
  EXPECT_NEAR(at(99.0), s0 * 1.06, 1e-4 * s0);
  EXPECT_LT(std::abs(at(99.0) - at(90.0)), 1e-4 * s0);

  c.creep.enabled = false;
  const auto off = run_field(c, e);
  EXPECT_DOUBLE_EQ(off[20].s, off.back().s);
}

TEST(PlantEffects, LeakageDecaysHeldChargeWithTheConfiguredTimeConstant) {
  PlantConfig c{};
  c.sample_rate_hz = 10000.0;
  c.charge_amplifier.leakage_enabled = true;
  c.charge_amplifier.leakage_tau_s = 0.5;
  const auto e = step_field(10, 20000, 1.0e6);
  const auto on = run_field(c, e);
  const double d1 = on[10 + 1000].d_meas_c_per_m2;   // t = 0.1 s after the step
  const double d2 = on[10 + 11000].d_meas_c_per_m2;  // t = 1.1 s
  const double tau = 1.0 / std::log(d1 / d2);
  EXPECT_NEAR(tau, 0.5, 0.5e-3);
  EXPECT_NEAR(on.back().d_c_per_m2, 0.02, 1e-12);  // the true charge stays

  c.charge_amplifier.leakage_enabled = false;
  const auto off = run_field(c, e);
  EXPECT_DOUBLE_EQ(off.back().d_meas_c_per_m2, off[1010].d_meas_c_per_m2);
}

TEST(PlantEffects, ChargeOffsetDrifts) {
  PlantConfig c{};
  c.sample_rate_hz = 1000.0;
  c.charge_amplifier.drift_enabled = true;
  c.charge_amplifier.offset_c = 1e-8;
  c.charge_amplifier.drift_c_per_s = 1e-8;
  c.charge_amplifier.random_walk_c_per_sqrt_s = 0.0;
  const auto out = run_field(c, std::vector<double>(10001, 0.0));
  const double area = 167 * 25e-6;
  // q_off(t) = offset + drift t: the offset at t = 0, and t = 10 s at the last sample.
  EXPECT_NEAR(out.front().q_amp_c, 1e-8, 1e-20);
  EXPECT_NEAR(out.back().d_meas_c_per_m2 * area, 1e-8 + 10.0 * 1e-8, 1e-16);
  EXPECT_DOUBLE_EQ(out.back().q_c, 0.0);  // the stack's charge does not drift
}

double ringing_frequency(const std::vector<StepOutput>& out, std::size_t from, double fs) {
  const double final = out.back().s;
  std::vector<double> crossings;
  for (std::size_t k = from; k + 1 < std::min(out.size(), from + 2000); ++k) {
    const double a = out[k].s - final;
    const double b = out[k + 1].s - final;
    if (a < 0.0 && b >= 0.0) crossings.push_back(static_cast<double>(k) + a / (a - b));
  }
  if (crossings.size() < 3) return 0.0;
  return fs * static_cast<double>(crossings.size() - 1) / (crossings.back() - crossings.front());
}

TEST(PlantEffects, ResonanceRingsAtTheConfiguredFrequency) {
  PlantConfig c{};
  c.mechanics.enabled = true;
  c.mechanics.resonance_hz = 6000.0;
  c.mechanics.damping_ratio = 0.01;
  c.mechanics.load_stiffness_n_per_m = 1e7;
  const auto e = step_field(10, 5000, 1.0e6);
  const auto on = run_field(c, e);
  const double f = ringing_frequency(on, 10, c.sample_rate_hz);
  EXPECT_NEAR(f, 6000.0 * std::sqrt(1.0 - 0.01 * 0.01), 6.0);
  const double peak =
      std::max_element(on.begin(), on.end(), [](auto& a, auto& b) { return a.s < b.s; })->s;
  EXPECT_GT(peak, 1.8 * on.back().s);  // a lightly damped step overshoots almost 100 %

  c.mechanics.enabled = false;
  const auto off = run_field(c, e);
  EXPECT_DOUBLE_EQ(off[11].s, off.back().s);
  // Quasi-static: the load spring takes its share of the free stroke.
  const double k_s = derive(c).stack_stiffness_n_per_m;
  EXPECT_NEAR(off.back().s, 5.5e-4 * k_s / (k_s + 1e7), 1e-12);
}

TEST(PlantEffects, CompressiveStressShrinksTheLoop) {
  PlantConfig c{};
  c.sample_rate_hz = 10000.0;
  c.hysteresis.enabled = true;
  const auto e = cosine_cycles(c.sample_rate_hz, 5.0, 2);
  const std::size_t half = e.size() / 2;
  auto width = [&](const PlantConfig& config, double force_n) {
    const auto out = run_field(config, e, force_n);
    return test::loop_height(out, half, out.size(), 1.0e6, 2e4, e_of, d_of);
  };
  const double free_width = width(c, 0.0);
  EXPECT_NEAR(width(c, -800.0) / free_width, 1.0, 1e-6);  // stress effect off
  c.stress.enabled = true;
  EXPECT_NEAR(width(c, 0.0) / free_width, 1.0, 0.02);
  EXPECT_LT(width(c, -800.0) / free_width, 0.7);
}

TEST(PlantEffects, SlewLimitBoundsTheFieldRate) {
  PlantConfig c{};
  c.amplifier.enabled = true;
  c.amplifier.slew_rate_v_per_s = 1.0e5;
  c.amplifier.current_limit_a = 10.0;
  const auto e = step_field(10, 1000, 1.5e6);
  const auto on = run_field(c, e);
  const double limit = 1.0e5 / c.geometry.layer_thickness_m / c.sample_rate_hz;
  double max_step = 0.0;
  bool flagged = false;
  for (std::size_t k = 1; k < on.size(); ++k) {
    max_step = std::max(max_step, std::abs(on[k].e_v_per_m - on[k - 1].e_v_per_m));
    flagged = flagged || (on[k].status & kSlewLimited) != 0U;
  }
  EXPECT_LE(max_step, limit * (1.0 + 1e-9));
  EXPECT_GT(max_step, 0.99 * limit);
  EXPECT_TRUE(flagged);
  EXPECT_NEAR(on.back().e_v_per_m, 1.5e6, 1e-6);

  c.amplifier.enabled = false;
  const auto off = run_field(c, e);
  EXPECT_DOUBLE_EQ(off[10].e_v_per_m, 1.5e6);
}

TEST(PlantEffects, CurrentLimitBoundsTheChargingCurrent) {
  PlantConfig c{};
  c.amplifier.enabled = true;
  c.amplifier.slew_rate_v_per_s = 1.0e8;
  c.amplifier.current_limit_a = 0.2;
  const auto on = run_field(c, step_field(10, 2000, 2.0e6));
  double max_current = 0.0;
  for (std::size_t k = 1; k < on.size(); ++k) {
    max_current = std::max(max_current, std::abs(on[k].q_c - on[k - 1].q_c) * c.sample_rate_hz);
  }
  EXPECT_LE(max_current, 0.2 * 1.001);
  EXPECT_GT(max_current, 0.19);
  EXPECT_TRUE((on[20].status & kCurrentLimited) != 0U);
}

TEST(PlantEffects, VoltageRangeClipsTheCommand) {
  PlantConfig c{};
  c.amplifier.enabled = true;
  c.amplifier.slew_rate_v_per_s = 1.0e9;
  c.amplifier.current_limit_a = 1.0e3;
  const auto on = run_field(c, step_field(1, 10, 3.0e6));
  EXPECT_DOUBLE_EQ(on.back().u_v, c.amplifier.voltage_max_v);
  EXPECT_TRUE((on.back().status & kVoltageClipped) != 0U);
}

TEST(PlantEffects, QuantisationGivesTheConfiguredStep) {
  PlantConfig c{};
  c.sensors.d.adc = AdcConfig{true, 10, -0.05, 0.15};
  const double lsb = 0.2 / 1023.0;
  std::vector<double> e(20000);
  for (std::size_t k = 0; k < e.size(); ++k)
    e[k] = 2.0e6 * static_cast<double>(k) / 20000.0;
  const auto out = run_field(c, e);
  std::set<double> levels;
  for (const auto& o : out) {
    const double code = (o.d_meas_c_per_m2 + 0.05) / lsb;
    ASSERT_NEAR(code, std::round(code), 1e-6);
    EXPECT_LE(std::abs(o.d_meas_c_per_m2 - o.d_c_per_m2), 0.5 * lsb + 1e-12);
    levels.insert(o.d_meas_c_per_m2);
  }
  double smallest = 1.0;
  for (auto it = std::next(levels.begin()); it != levels.end(); ++it) {
    smallest = std::min(smallest, *it - *std::prev(it));
  }
  EXPECT_NEAR(smallest, lsb, 1e-12);
  EXPECT_EQ(levels.size(), 205U);  // 0 .. 0.04 C/m^2 spans 0.04 / lsb + 1 codes
}

TEST(PlantEffects, DelayShiftsTheChannelBySamples) {
  PlantConfig c{};
  c.sensors.e.delay_samples = 3;
  std::vector<double> e(50);
  for (std::size_t k = 0; k < e.size(); ++k)
    e[k] = 1e4 * static_cast<double>(k);
  const auto out = run_field(c, e);
  for (std::size_t k = 3; k < out.size(); ++k) {
    EXPECT_DOUBLE_EQ(out[k].e_meas_v_per_m, out[k - 3].e_v_per_m);
  }
  EXPECT_DOUBLE_EQ(out[1].e_meas_v_per_m, 0.0);
}

TEST(PlantEffects, NoiseHasTheConfiguredStandardDeviation) {
  PlantConfig c{};
  c.sensors.d.noise_std = 1e-4;
  const auto out = run_field(c, std::vector<double>(20000, 1.0e6));
  double sum2 = 0.0;
  for (const auto& o : out)
    sum2 += std::pow(o.d_meas_c_per_m2 - o.d_c_per_m2, 2);
  EXPECT_NEAR(std::sqrt(sum2 / static_cast<double>(out.size())), 1e-4, 3e-6);
}

TEST(PlantEffects, PermittivityDependsOnTheFieldOnlyWhenOn) {
  PlantConfig c{};
  const auto ratio = [](const PlantConfig& config) {
    const double low = run_field(config, {0.5e6}).back().d_c_per_m2 / 0.5e6;
    const double high = run_field(config, {2.0e6}).back().d_c_per_m2 / 2.0e6;
    return high / low;
  };
  EXPECT_NEAR(ratio(c), 1.0, 1e-12);
  c.permittivity.enabled = true;
  EXPECT_NEAR(ratio(c), (1.0 + 0.25 + 0.1) / (1.0 + 0.0625 + 0.00625), 1e-9);
}

TEST(PlantEffects, TemperatureChangesTheCoefficientsOnlyWhenOn) {
  PlantConfig c{};
  c.mechanics.load_stiffness_n_per_m = 5e7;  // a partly blocked stack: stress depends on s^E
  const auto at = [](const PlantConfig& config, double temp) {
    return run_field(config, {1.0e6}, 0.0, temp).back();
  };
  EXPECT_DOUBLE_EQ(at(c, 25.0).s, at(c, 75.0).s);
  EXPECT_DOUBLE_EQ(at(c, 25.0).d_c_per_m2, at(c, 75.0).d_c_per_m2);
  c.temperature.enabled = true;
  const StepOutput hot = at(c, 75.0);
  // Quasi-static against the load spring: S = k_s / (k_s + k_l) d E, T = (S - d E) / s^E,
  // D = eps E + d T, every coefficient scaled by 1 + k (75 - 25).
  const double d = 5.5e-10 * (1.0 + 50.0 * 2e-3);
  const double compliance = 3.5e-11 * (1.0 + 50.0 * 5e-4);
  const double k_s = 25e-6 / (compliance * derive(c).length_m);
  const double strain = k_s / (k_s + 5e7) * d * 1.0e6;
  const double stress = (strain - d * 1.0e6) / compliance;
  EXPECT_NEAR(hot.s / strain, 1.0, 1e-12);
  EXPECT_NEAR(hot.t_pa / stress, 1.0, 1e-12);
  EXPECT_NEAR(hot.d_c_per_m2 / (2.0e-8 * (1.0 + 50.0 * 4e-3) * 1.0e6 + d * stress), 1.0, 1e-12);
}

// Aging (config.hpp AgingConfig): from start_s the coupling d (and the loops) lose
// polarisation_loss_per_h and the permittivity capacitance_loss_per_h, linearly in time; the
// leakage's charge sum(n A sigma(t) E Ts) reaches the charge amplifier. Off: nothing changes.
TEST(PlantEffects, AgingLowersCouplingAndCapacitanceAndLeaksChargeOnlyWhenOn) {
  PlantConfig c{};
  c.sample_rate_hz = 10.0;
  c.aging.polarisation_loss_per_h = 0.05;
  c.aging.capacitance_loss_per_h = 0.02;
  c.aging.start_s = 600.0;
  const std::vector<double> held(42001, 1.0e6);  // 4200 s at 1 MV/m, free stack
  const std::vector<StepOutput> off = run_field(c, held);
  c.aging.enabled = true;
  const std::vector<StepOutput> on = run_field(c, held);
  EXPECT_DOUBLE_EQ(off.back().s, off[6000].s);
  EXPECT_DOUBLE_EQ(on[6000].s, off[6000].s);  // not yet aging at 600 s
  EXPECT_NEAR(on.back().s / off.back().s, 0.95, 1e-9);
  EXPECT_NEAR(on.back().d_c_per_m2 / off.back().d_c_per_m2, 0.98, 1e-9);
  // Leakage: rho 1e10 Ohm m, the conductivity doubling per hour from the start.
  PlantConfig l{};
  l.sample_rate_hz = 10.0;
  l.aging.enabled = true;
  l.aging.leakage_resistivity_ohm_m = 1e10;
  l.aging.leakage_growth_per_h = 1.0;
  const std::vector<StepOutput> leak = run_field(l, std::vector<double>(36001, 1.0e6));
  // sum over k = 0 .. n-1 of (1 + t_k / 3600) / rho E Ts, t_k = k Ts: about 1.5 E 3600 / rho.
  double expected = 0.0;
  for (int k = 0; k <= 36000; ++k)
    expected += (1.0 + k * 0.1 / 3600.0) / 1e10 * 1.0e6 * 0.1;
  EXPECT_NEAR((leak.back().d_meas_c_per_m2 - leak.back().d_c_per_m2) / expected, 1.0, 1e-6);
  EXPECT_DOUBLE_EQ(off.back().d_meas_c_per_m2, off.back().d_c_per_m2);
  std::string why;
  l.aging.start_s = -1.0;
  EXPECT_FALSE(l.is_valid(&why));
  EXPECT_NE(why.find("plant.aging.start_s"), std::string::npos) << why;
}

// The stress-dependent coefficients see the stress of the same sample: the recorded S, T and D
// satisfy S = d(T) E + s^E T and D = eps(T) E + d(T) T at every sample, also at a force step.
TEST(PlantEffects, StressFeedbackIsSelfConsistentAtEverySample) {
  PlantConfig c{};
  c.stress.enabled = true;
  c.mechanics.load_stiffness_n_per_m = 2e7;
  std::vector<StepInput> in(20, StepInput{2.0e6, 0.0, 25.0});
  for (std::size_t k = 10; k < in.size(); ++k)
    in[k].force_n = -800.0;
  const auto out = simulate(c, in);
  const StressConfig& st = c.stress;
  for (std::size_t k = 0; k < out.size(); ++k) {
    SCOPED_TRACE(k);
    const StepOutput& o = out[k];
    const double d = 5.5e-10 * (1.0 + st.d_coefficient_per_pa * o.t_pa);
    const double eps = 2.0e-8 * (1.0 + st.permittivity_coefficient_per_pa * o.t_pa);
    EXPECT_NEAR(o.s, d * o.e_v_per_m + 3.5e-11 * o.t_pa, 1e-12 * std::abs(o.s) + 1e-18);
    EXPECT_NEAR(o.d_c_per_m2, eps * o.e_v_per_m + d * o.t_pa, 1e-12 * std::abs(o.d_c_per_m2));
  }
  EXPECT_LT(out[10].t_pa, -1.0e7);  // the step did compress the stack
}

// Without dissipative effects the stack is conservative: stress-dependent coupling at a fast,
// large cycle against a stiff load neither dissipates nor generates electrical energy.
TEST(PlantEffects, StressCouplingGeneratesNoEnergy) {
  PlantConfig c{};
  c.stress.enabled = true;
  c.mechanics.load_stiffness_n_per_m = 5e7;
  const auto e = cosine_cycles(c.sample_rate_hz, 500.0, 3);
  const auto out = run_field(c, e);
  const std::size_t cycle = e.size() / 3;
  EXPECT_NEAR(test::loop_energy(out, cycle, 2 * cycle), 0.0, 1e-6);  // J/m^3
}

// The terminal values are the field values through the geometry (docs/recording-format.md).
TEST(PlantEffects, TerminalValuesFollowTheGeometry) {
  PlantConfig c{};
  c.hysteresis.enabled = true;
  c.creep.enabled = true;
  c.mechanics.enabled = true;
  c.mechanics.load_force_n = -300.0;
  c.charge_amplifier.leakage_enabled = true;
  c.charge_amplifier.drift_enabled = true;
  c.charge_amplifier.offset_c = 1e-7;
  const auto out = run_field(c, cosine_cycles(c.sample_rate_hz, 200.0, 1));
  const double h = c.geometry.layer_thickness_m;
  const double area = c.geometry.layers * c.geometry.electrode_area_m2;
  const double length = derive(c).length_m;
  for (const StepOutput& o : out) {
    EXPECT_NEAR(o.u_v, o.e_v_per_m * h, 1e-12);
    EXPECT_NEAR(o.q_c, o.d_c_per_m2 * area, 1e-18);
    EXPECT_NEAR(o.x_m, o.s * length, 1e-18);
    EXPECT_NEAR(o.f_n, o.t_pa * c.geometry.cross_section_m2, 1e-9);
    EXPECT_NEAR(o.d_meas_c_per_m2, o.q_amp_c / area, 1e-15);  // ideal sensor on the amplifier
  }
  EXPECT_GT(std::abs(out.back().q_amp_c - out.back().q_c), 5e-8);  // leakage and offset
}

}  // namespace
}  // namespace selfsense::plant
