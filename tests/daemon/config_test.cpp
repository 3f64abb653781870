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
  for (const char* name : {"sim.yaml", "selfsensed.yaml"}) {
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

}  // namespace
}  // namespace selfsense::daemon
