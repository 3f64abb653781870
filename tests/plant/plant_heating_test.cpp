// Self-heating (plant.heating, issue 24 item 4): a fast sine warms the simulated stack to the
// first-order steady state R_th P, P the electrical power it takes, here measured at its
// terminals (the mean of u dq/dt over whole drive cycles, apart from the plant's own sum on
// E and D), and with the time constant tau; off by default, the stack stays at the input
// temperature. The daemon's bench (config/plant/daemon.yaml, 20 kHz) with the temperature
// model on, a 200 Hz sine of 0.2 .. 1.8 MV/m; tau 5 s for CI time (the default is 120 s).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>

#include "selfsense/plant/plant.hpp"
#include "selfsense/plant_io/plant_yaml.hpp"

namespace selfsense::plant {
namespace {

constexpr double kAmbient = 25.0;  // [degC]
constexpr double kHz = 200.0;
constexpr double kTau = 5.0;   // [s]
constexpr double kRth = 50.0;  // [K/W], the default

PlantConfig bench(bool heating) {
  const std::filesystem::path root(SELFSENSE_SOURCE_DIR);
  PlantConfig c = load_plant_file(root / "config/plant/daemon.yaml").plant;
  c.temperature.enabled = true;
  c.heating.enabled = heating;
  c.heating.thermal_resistance_k_per_w = kRth;
  c.heating.time_constant_s = kTau;
  return c;
}

struct HeatingRun {
  double rise_at_tau{0.0};  // [K]
  double rise_end{0.0};     // [K], after 10 tau
  double power_w{0.0};      // terminal power over the last second's whole cycles
};

HeatingRun run(bool heating) {
  Plant plant(bench(heating));
  const double fs = 1.0 / plant.sample_time_s();
  const auto per_cycle = static_cast<long>(std::lround(fs / kHz));
  const long n = static_cast<long>(10.0 * kTau * fs);
  const long measured_from = n - 200 * per_cycle;  // the last 200 cycles (1 s)
  HeatingRun out;
  double energy = 0.0;
  double u_prev = 0.0;
  double q_prev = 0.0;
  for (long k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) / fs;
    const double e = 1.0e6 - 0.8e6 * std::cos(2.0 * std::numbers::pi * kHz * t);
    const StepOutput o = plant.step(StepInput{e, 0.0, kAmbient});
    if (k >= measured_from) energy += 0.5 * (o.u_v + u_prev) * (o.q_c - q_prev);
    u_prev = o.u_v;
    q_prev = o.q_c;
    if (k == static_cast<long>(kTau * fs)) out.rise_at_tau = o.temp_degc - kAmbient;
    out.rise_end = o.temp_degc - kAmbient;
  }
  out.power_w = energy / (static_cast<double>(n - measured_from) / fs);
  return out;
}

TEST(PlantHeating, AFastSineWarmsTheStackToRthTimesItsPower) {
  const HeatingRun r = run(true);
  const double expected = kRth * r.power_w;
  std::printf(
      "self-heating: P %.4f W, R_th P %.2f K, rise %.2f K after 10 tau, %.2f K after tau "
      "(%.1f %% of it)\n",
      r.power_w, expected, r.rise_end, r.rise_at_tau, 100.0 * r.rise_at_tau / r.rise_end);
  EXPECT_GT(r.power_w, 0.0);
  EXPECT_NEAR(r.rise_end, expected, 0.1 * expected);
  // First order: 1 - 1/e = 63 % after one time constant (the power falls a little as it warms).
  EXPECT_NEAR(r.rise_at_tau / r.rise_end, 1.0 - std::exp(-1.0), 0.05);
}

TEST(PlantHeating, OffTheStackStaysAtTheInputTemperature) {
  EXPECT_FALSE(PlantConfig{}.heating.enabled);
  const HeatingRun r = run(false);
  EXPECT_EQ(r.rise_end, 0.0);
  EXPECT_GT(r.power_w, 0.0);
}

}  // namespace
}  // namespace selfsense::plant
