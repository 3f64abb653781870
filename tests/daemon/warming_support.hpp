// The daemon tests' warming stack: config/sim.yaml on config/plant/daemon.yaml with the plant's
// temperature model on and the simulated driver's temperature ramp (docs/daemon.md,
// "Adaptation"), and the requests the adaptation tests make.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "daemon/running_daemon.hpp"

namespace selfsense::daemon::testing {

inline const std::filesystem::path kSource = SELFSENSE_SOURCE_DIR;

// config/plant/daemon.yaml with the temperature model of config/plant/temperature.yaml (its
// coefficients are the plant's defaults) as dir/plant.yaml.
inline std::filesystem::path warming_plant(const std::filesystem::path& dir) {
  std::filesystem::path plant = dir / "plant.yaml";  // returned: moved, so not const
  testing::write_text(
      plant, test::edited(testing::read_text(kSource / "config" / "plant" / "daemon.yaml"),
                          {{"  hysteresis: {enabled: true}",
                            "  hysteresis: {enabled: true}\n  temperature: {enabled: true}"}},
                          "config/plant/daemon.yaml"));
  return plant;
}

// config/sim.yaml on the warming plant, start_degc -> end_degc over ramp_s, adaptation on or
// off, with `extra` edits.
inline std::string warming_config(const std::filesystem::path& dir, bool adapt, double ramp_s,
                                  std::vector<std::pair<std::string, std::string>> extra = {}) {
  const std::filesystem::path plant = warming_plant(dir);
  extra.emplace_back("plant: " + (kSource / "config" / "plant" / "daemon.yaml").string(),
                     "plant: " + plant.string() +
                         "\n  temperature: {start_degc: 25.0, end_degc: 45.0, ramp_s: " +
                         std::to_string(ramp_s) + "}");
  if (adapt) extra.emplace_back("adaptation:\n  enabled: false", "adaptation:\n  enabled: true");
  return testing::scratch_config(dir, extra);
}

inline nlohmann::json adaptation_of(RunningDaemon& daemon) {
  const nlohmann::json reply = daemon.request(R"({"request": "adapt", "action": "show"})");
  EXPECT_TRUE(reply.value("ok", false)) << reply.dump();
  return reply["adaptation"];
}

inline void play_sine(RunningDaemon& daemon) {
  ASSERT_TRUE(daemon.reset_and_arm()) << daemon.status().dump();
  const nlohmann::json wave =
      daemon.request(R"({"request": "wave", "shape": "sine", "amplitude": 4e-4, "offset": 6e-4,)"
                     R"( "frequency_hz": 2, "phase": 0, "repeat": 0})");
  ASSERT_TRUE(wave.value("ok", false)) << wave.dump();
}

}  // namespace selfsense::daemon::testing
