// The daemon's configuration: the shipped examples load, and every kind of mistake is named with
// file, line and key path, all problems at once.
#include "selfsense/daemon/config.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "registry/registry.hpp"

namespace selfsense::daemon {
namespace {

const std::filesystem::path kConfigDir = std::filesystem::path(SELFSENSE_SOURCE_DIR) / "config";

// Writes a configuration beside the shipped ones (so models/ and plant/ resolve).
std::filesystem::path write(const std::string& name, const std::string& text) {
  std::filesystem::path path = kConfigDir / (".test-" + name + ".yaml");
  std::ofstream(path) << text;
  return path;
}

std::string sim_with(const std::string& from, const std::string& to) {
  std::ifstream in(kConfigDir / "sim.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

ConfigResult load(const std::filesystem::path& path) {
  drivers::Registry registry;
  ConfigResult r = load_config(path, &registry);
  std::filesystem::remove(path);
  return r;
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
  const ConfigResult r =
      load(write("unknown", sim_with("  priority: 80", "  priority: 80\n  prio: 3")));
  ASSERT_FALSE(r.ok());
  EXPECT_TRUE(has(r, ".test-unknown.yaml:")) << r.problems.front();
  EXPECT_TRUE(has(r, "loop.prio")) << r.problems.front();
}

TEST(DaemonConfig, TheCpuLatencyRequestIsReadAndBounded) {
  const ConfigResult shipped = load(write("latency", sim_with("rate_hz: 10000", "rate_hz: 10000")));
  ASSERT_TRUE(shipped.ok()) << shipped.problems.front();
  EXPECT_EQ(shipped.config.loop.cpu_dma_latency_us, 0);
  const ConfigResult none =
      load(write("latency", sim_with("cpu_dma_latency_us: 0", "cpu_dma_latency_us: -1")));
  ASSERT_TRUE(none.ok()) << none.problems.front();
  EXPECT_EQ(none.config.loop.cpu_dma_latency_us, -1);
  const ConfigResult bad =
      load(write("latency", sim_with("cpu_dma_latency_us: 0", "cpu_dma_latency_us: -5")));
  EXPECT_TRUE(has(bad, ".test-latency.yaml:9: loop.cpu_dma_latency_us: -5 must be -1"))
      << (bad.problems.empty() ? "" : bad.problems.front());
}

TEST(DaemonConfig, EveryValueProblemIsReportedAtOnce) {
  std::string text = sim_with("rate_hz: 10000", "rate_hz: 3000");  // notch 2 kHz > 0.45 fs
  const std::size_t at = text.find("priority: 80");
  text.replace(at, 12, "priority: 120");
  const ConfigResult r = load(write("values", text));
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
  const ConfigResult r = load(write("cross", sim_with("  setpoint_strain: [-5.0e-4, 1.5e-3]",
                                                      "  setpoint_strain: [-5.0e-4, 3.0e-3]")));
  EXPECT_TRUE(has(r, "safety.setpoint_strain: must be an interval inside safety.strain_range"));
  const ConfigResult safe =
      load(write("safe", sim_with("safe_value_v_per_m: 0.0", "safe_value_v_per_m: 3.0e6")));
  EXPECT_TRUE(has(safe, "safety.safe_value_v_per_m: must be inside control.command_v_per_m"));
}

TEST(DaemonConfig, ModelAndDriverProblemsAreNamed) {
  const ConfigResult missing =
      load(write("model", sim_with("model: models/sim.yaml", "model: models/none.yaml")));
  EXPECT_TRUE(has(missing, "model: ")) << missing.problems.front();
  const ConfigResult driver = load(write("driver", sim_with("type: simulated", "type: ethercat")));
  EXPECT_TRUE(has(
      driver, "driver.type: 'ethercat' is not one of simulated, can, modbus-tcp, modbus-rtu, spi"))
      << driver.problems.front();
  const ConfigResult mode = load(write("mode", sim_with("mode: position", "mode: speed")));
  EXPECT_TRUE(has(mode, "control.mode: 'speed' is not one of position, force, open-loop, damping"));
  const ConfigResult version = load(write("version", sim_with("selfsensed: 1", "selfsensed: 2")));
  EXPECT_TRUE(has(version, "selfsensed: format version 2 is not supported"));
}

}  // namespace
}  // namespace selfsense::daemon
