// The daemon's configuration: the shipped examples load, and every kind of mistake is named with
// file, line and key path, all problems at once.
#include "selfsense/daemon/config.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "selfsense/drivers/registry/registry.hpp"
#include "support/config_edits.hpp"

namespace selfsense::daemon {
namespace {

const std::filesystem::path kConfigDir = test::shipped_config_dir();

// config/sim.yaml with the edits, loaded as .test-NAME.yaml from a scratch directory.
ConfigResult load_sim(const std::string& name, const test::Edits& edits) {
  drivers::Registry registry;
  return test::load_shipped_with("sim.yaml", edits, registry, ".test-" + name + ".yaml");
}

bool has(const ConfigResult& r, const std::string& text) {
  for (const std::string& p : r.problems) {
    if (p.find(text) != std::string::npos) return true;
  }
  return false;
}

TEST(DaemonConfig, ShippedConfigurationsLoad) {
  for (const char* name : {"sim.yaml", "selfsensed.yaml", "heating-sim.yaml"}) {
    drivers::Registry registry;
    const ConfigResult r = load_config(kConfigDir / name, &registry);
    EXPECT_TRUE(r.ok()) << name << ": " << (r.problems.empty() ? "" : r.problems.front());
  }
  drivers::Registry registry;
  const ConfigResult r = load_config(kConfigDir / "sim.yaml", &registry);
  EXPECT_EQ(r.config.loop.rate_hz, 10000.0);
  EXPECT_EQ(r.config.control.filter_count, 2U);
  EXPECT_EQ(r.config.control.mode, runtime::ControlMode::kPosition);
  EXPECT_NE(registry.create(), nullptr);
}

// The simulated bench runs on shared machines, whose kernels make runs of late cycles: only a
// 0.2 s stall faults there. The service's configuration keeps a real-time board's policy.
TEST(DaemonConfig, TheSimulatedBenchHoldsASharedMachineAndTheServiceIsStrict) {
  drivers::Registry sim_registry;
  const ConfigResult sim = load_config(kConfigDir / "sim.yaml", &sim_registry);
  ASSERT_TRUE(sim.ok()) << sim.problems.front();
  EXPECT_EQ(sim.config.safety.overrun.consecutive, 2000U);
  EXPECT_EQ(sim.config.safety.overrun.within_count, 0U);
  drivers::Registry board_registry;
  const ConfigResult board = load_config(kConfigDir / "selfsensed.yaml", &board_registry);
  ASSERT_TRUE(board.ok()) << board.problems.front();
  EXPECT_EQ(board.config.safety.overrun, (runtime::OverrunPolicy{3, 10, 10000}));
}

TEST(DaemonConfig, UnknownKeysAreNamedWithTheirLine) {
  const ConfigResult r = load_sim("unknown", {{"  priority: 80", "  priority: 80\n  prio: 3"}});
  ASSERT_FALSE(r.ok());
  EXPECT_TRUE(has(r, ".test-unknown.yaml:")) << r.problems.front();
  EXPECT_TRUE(has(r, "loop.prio")) << r.problems.front();
}

TEST(DaemonConfig, TheCpuLatencyRequestIsReadAndBounded) {
  const ConfigResult shipped = load_sim("latency", {{"rate_hz: 10000", "rate_hz: 10000"}});
  ASSERT_TRUE(shipped.ok()) << shipped.problems.front();
  EXPECT_EQ(shipped.config.loop.cpu_dma_latency_us, 0);
  const ConfigResult none =
      load_sim("latency", {{"cpu_dma_latency_us: 0", "cpu_dma_latency_us: -1"}});
  ASSERT_TRUE(none.ok()) << none.problems.front();
  EXPECT_EQ(none.config.loop.cpu_dma_latency_us, -1);
  const ConfigResult bad =
      load_sim("latency", {{"cpu_dma_latency_us: 0", "cpu_dma_latency_us: -5"}});
  EXPECT_TRUE(has(bad, ".test-latency.yaml:9: loop.cpu_dma_latency_us: -5 must be -1"))
      << (bad.problems.empty() ? "" : bad.problems.front());
}

TEST(DaemonConfig, EveryValueProblemIsReportedAtOnce) {
  const ConfigResult r = load_sim("values", {{"rate_hz: 10000", "rate_hz: 3000"},  // notch 2 kHz
                                             {"priority: 80", "priority: 120"}});
  EXPECT_TRUE(has(r, "loop.priority: 120 must be within [1, 99]"));
  EXPECT_TRUE(
      has(r, "control.filters[0].frequency_hz: 2000 Hz must be below 0.45 of the loop rate"));
  EXPECT_TRUE(has(r, "control.filters[1].frequency_hz"));
  EXPECT_TRUE(has(r, "control.damping: DampingController.frequency"));
  EXPECT_TRUE(has(r, "driver.plant: the plant's sample_rate_hz 20000"));  // 4 kHz does not divide
  EXPECT_GE(r.problems.size(), 5U);
  for (const std::string& p : r.problems)
    EXPECT_NE(p.find(".test-values.yaml:"), std::string::npos) << p;
}

TEST(DaemonConfig, CrossFieldRules) {
  const ConfigResult r = load_sim(
      "cross", {{"  setpoint_strain: [-5.0e-4, 1.5e-3]", "  setpoint_strain: [-5.0e-4, 3.0e-3]"}});
  EXPECT_TRUE(has(r, "safety.setpoint_strain: must be an interval inside safety.strain_range"));
  const ConfigResult safe =
      load_sim("safe", {{"safe_value_v_per_m: 0.0", "safe_value_v_per_m: 3.0e6"}});
  EXPECT_TRUE(has(safe, "safety.safe_value_v_per_m: must be inside control.command_v_per_m"));
}

TEST(DaemonConfig, ModelAndDriverProblemsAreNamed) {
  const ConfigResult missing =
      load_sim("model", {{"model: models/sim.yaml", "model: models/none.yaml"}});
  EXPECT_TRUE(has(missing, "model: ")) << missing.problems.front();
  const ConfigResult driver = load_sim("driver", {{"type: simulated", "type: ethercat"}});
  EXPECT_TRUE(has(
      driver, "driver.type: 'ethercat' is not one of simulated, can, modbus-tcp, modbus-rtu, spi"))
      << driver.problems.front();
  const ConfigResult mode = load_sim("mode", {{"mode: position", "mode: speed"}});
  EXPECT_TRUE(has(mode, "control.mode: 'speed' is not one of position, force, open-loop, damping"));
  const ConfigResult version = load_sim("version", {{"selfsensed: 1", "selfsensed: 2"}});
  EXPECT_TRUE(has(version, "selfsensed: format version 2 is not supported"));
}

// adaptation: plain keys with DriftEstimatorConfig's defaults, strict, validated with its
// is_valid() under the section's name, at the key's line.
TEST(DaemonConfig, TheAdaptationSectionIsReadStrictlyAndValidated) {
  drivers::Registry registry;
  const ConfigResult shipped = load_config(kConfigDir / "sim.yaml", &registry);
  ASSERT_TRUE(shipped.ok()) << shipped.problems.front();
  EXPECT_FALSE(shipped.config.adaptation.enabled);
  adaptation::DriftEstimatorConfig bench;  // the defaults, and the bench's load spring
  bench.load_stiffness_ratio = 0.21;
  EXPECT_EQ(shipped.config.adaptation.estimator, bench);

  const ConfigResult on = load_sim("adapt", {{"  enabled: false                # true: the loop",
                                              "  enabled: true                 # true: the loop"},
                                             {"memory_updates: 500", "memory_updates: 800"},
                                             {"  frozen: false ", "  frozen: true  "}});
  ASSERT_TRUE(on.ok()) << on.problems.front();
  EXPECT_TRUE(on.config.adaptation.enabled);
  EXPECT_TRUE(on.config.adaptation.estimator.frozen);
  EXPECT_EQ(on.config.adaptation.estimator.memory_updates, 800.0);
  EXPECT_FALSE(on.config.adaptation.use_temperature);
  EXPECT_FALSE(on.config.loop_config().adaptation_temperature);
  // The driver's temperature into the adaptation: only with the adaptation on.
  const ConfigResult temp =
      load_sim("adapt-temp", {{"  enabled: false                # true: the loop",
                               "  enabled: true                 # true: the loop"},
                              {"use_temperature: false", "use_temperature: true"}});
  ASSERT_TRUE(temp.ok()) << temp.problems.front();
  EXPECT_TRUE(temp.config.adaptation.use_temperature);
  EXPECT_TRUE(temp.config.loop_config().adaptation_temperature);
  const ConfigResult temp_off =
      load_sim("adapt-temp-off", {{"use_temperature: false", "use_temperature: true"}});
  ASSERT_TRUE(temp_off.ok()) << temp_off.problems.front();
  EXPECT_FALSE(temp_off.config.loop_config().adaptation_temperature);
  const ConfigResult temp_bad =
      load_sim("adapt-temp-bad", {{"use_temperature: false", "use_temperature: 3"}});
  EXPECT_TRUE(has(temp_bad, "adaptation.use_temperature")) << temp_bad.problems.front();
  // The feedforward from the estimate: off as shipped, and only with the adaptation on.
  EXPECT_FALSE(shipped.config.adaptation.feedforward_estimate);
  EXPECT_FALSE(on.config.loop_config().adaptation_feedforward_estimate);
  const ConfigResult ff =
      load_sim("adapt-ff", {{"  enabled: false                # true: the loop",
                             "  enabled: true                 # true: the loop"},
                            {"feedforward_estimate: false", "feedforward_estimate: true"}});
  ASSERT_TRUE(ff.ok()) << ff.problems.front();
  EXPECT_TRUE(ff.config.adaptation.feedforward_estimate);
  EXPECT_TRUE(ff.config.loop_config().adaptation_feedforward_estimate);
  const ConfigResult ff_off =
      load_sim("adapt-ff-off", {{"feedforward_estimate: false", "feedforward_estimate: true"}});
  ASSERT_TRUE(ff_off.ok()) << ff_off.problems.front();
  EXPECT_FALSE(ff_off.config.loop_config().adaptation_feedforward_estimate);
  const ConfigResult ff_bad =
      load_sim("adapt-ff-bad", {{"feedforward_estimate: false", "feedforward_estimate: 0.5"}});
  EXPECT_TRUE(has(ff_bad, "adaptation.feedforward_estimate")) << ff_bad.problems.front();

  const ConfigResult bad = load_sim("adapt-bad", {{"memory_updates: 500", "memory_updates: 1"}});
  EXPECT_TRUE(has(bad, ".test-adapt-bad.yaml:")) << bad.problems.front();
  EXPECT_TRUE(has(bad, "adaptation.memory_updates: 1 must be > 1")) << bad.problems.front();
  const ConfigResult zero =
      load_sim("adapt-zero", {{"permittivity_per_k: 4.0e-3", "permittivity_per_k: 0.0"}});
  EXPECT_TRUE(has(zero, "adaptation.permittivity_per_k: 0 must not be 0")) << zero.problems.front();
  const ConfigResult mount =
      load_sim("adapt-mount", {{"load_stiffness_ratio: 0.21", "load_stiffness_ratio: -0.2"}});
  EXPECT_TRUE(has(mount, "adaptation.load_stiffness_ratio: -0.2 must be >= 0"))
      << mount.problems.front();
  // The thermal model's keys: read, and validated once it is on.
  const ConfigResult thermal = load_sim(
      "adapt-thermal", {{"thermal_model: false", "thermal_model: true"},
                        {"thermal_time_constant_s: 600.0", "thermal_time_constant_s: 20.0"}});
  ASSERT_TRUE(thermal.ok()) << thermal.problems.front();
  EXPECT_TRUE(thermal.config.adaptation.estimator.thermal.enabled);
  EXPECT_EQ(thermal.config.adaptation.estimator.thermal.time_constant_s, 20.0);
  EXPECT_EQ(thermal.config.adaptation.estimator.thermal.resistance_k_per_w, 50.0);
  const ConfigResult thermal_bad = load_sim(
      "adapt-thermal-bad", {{"thermal_model: false", "thermal_model: true"},
                            {"thermal_time_constant_s: 600.0", "thermal_time_constant_s: 0"}});
  EXPECT_TRUE(has(thermal_bad, "adaptation.thermal_time_constant_s: 0 must be > 0"))
      << thermal_bad.problems.front();
  const ConfigResult unknown = load_sim("adapt-unknown", {{"  compliance_per_k: 5.0e-4",
                                                           "  compliance_per_k: 5.0e-4\n"
                                                           "  forget: 3"}});
  EXPECT_TRUE(has(unknown, "adaptation.forget")) << unknown.problems.front();
}

// health: plain keys with the estimator's and the bands' defaults, strict, validated under the
// section's name at the key's line.
TEST(DaemonConfig, TheHealthSectionIsReadStrictlyAndValidated) {
  drivers::Registry registry;
  const ConfigResult shipped = load_config(kConfigDir / "sim.yaml", &registry);
  ASSERT_TRUE(shipped.ok()) << shipped.problems.front();
  EXPECT_FALSE(shipped.config.health.enabled);
  EXPECT_EQ(shipped.config.health.estimator, adaptation::HealthEstimatorConfig{});
  EXPECT_EQ(shipped.config.health.bands, adaptation::HealthBands{});
  EXPECT_FALSE(shipped.config.loop_config().health_enabled);

  const ConfigResult on =
      load_sim("health", {{"  enabled: false                # true: the loop runs the health",
                           "  enabled: true                 # true: the loop runs the health"},
                          {"  fault: false ", "  fault: true  "},
                          {"max_depolarisation_pct: 3.0", "max_depolarisation_pct: 4.5"},
                          {"baseline_cycles: 20", "baseline_cycles: 7"}});
  ASSERT_TRUE(on.ok()) << on.problems.front();
  EXPECT_TRUE(on.config.health.enabled);
  EXPECT_TRUE(on.config.health.bands.fault);
  EXPECT_EQ(on.config.health.bands.max_depolarisation_pct, 4.5);
  EXPECT_EQ(on.config.health.estimator.baseline_cycles, 7U);
  const runtime::LoopConfig lc = on.config.loop_config();
  EXPECT_TRUE(lc.health_enabled);
  EXPECT_TRUE(lc.health_bands.fault);
  EXPECT_EQ(lc.health.baseline_cycles, 7U);

  const ConfigResult slope =
      load_sim("health-slope", {{"slope_time_s: 600.0", "slope_time_s: 10.0"}});
  EXPECT_TRUE(has(slope, ".test-health-slope.yaml:")) << slope.problems.front();
  EXPECT_TRUE(has(slope, "health.slope_time_s: must be > trend_time_s")) << slope.problems.front();
  const ConfigResult band =
      load_sim("health-band", {{"max_depolarisation_pct: 3.0", "max_depolarisation_pct: 120"}});
  EXPECT_TRUE(has(band, "health.max_depolarisation_pct: 120 must be within (0, 100)"))
      << band.problems.front();
  const ConfigResult rho = load_sim(
      "health-rho", {{"min_leakage_resistivity_ohm_m: 1.0e9", "min_leakage_resistivity_ohm_m: 0"}});
  EXPECT_TRUE(has(rho, "health.min_leakage_resistivity_ohm_m: 0 must be > 0"))
      << rho.problems.front();
  const ConfigResult unknown = load_sim("health-unknown", {{"  dissipation_per_k: -4.0e-3",
                                                            "  dissipation_per_k: -4.0e-3\n"
                                                            "  humidity: 3"}});
  EXPECT_TRUE(has(unknown, "health.humidity")) << unknown.problems.front();
}

// The simulated stack's temperature ramp needs the plant's temperature model.
TEST(DaemonConfig, TheSimulatedTemperatureRampIsReadAndChecked) {
  const ConfigResult r =
      load_sim("ramp", {{"plant: plant/daemon.yaml",
                         "plant: plant/daemon.yaml\n  temperature: {start_degc: 25, end_degc: 45, "
                         "ramp_s: 30}"}});
  EXPECT_TRUE(has(r, "driver.temperature: the plant")) << (r.ok() ? "" : r.problems.front());
  const ConfigResult neg = load_sim(
      "ramp-neg", {{"plant: plant/daemon.yaml",
                    "plant: plant/temperature.yaml\n  temperature: {end_degc: 45, ramp_s: -1}"}});
  EXPECT_TRUE(has(neg, "driver.temperature: start_degc, end_degc must be finite and ramp_s"))
      << (neg.ok() ? "" : neg.problems.front());
  const ConfigResult swing = load_sim(
      "swing",
      {{"plant: plant/daemon.yaml",
        "plant: plant/temperature.yaml\n  temperature: {swing_degc: 5, swing_period_s: 0}"}});
  EXPECT_TRUE(has(swing, "driver.temperature: swing_degc must be finite and swing_period_s"))
      << (swing.ok() ? "" : swing.problems.front());
}

}  // namespace
}  // namespace selfsense::daemon
