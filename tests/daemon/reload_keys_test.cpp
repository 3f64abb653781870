// The reload table (reload_keys.hpp) against the loader: every key the strict loader knows has a
// reload class, every row is a key the loader knows, and a changed refused key is named.
#include "selfsense/daemon/reload_keys.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <set>
#include <string>

#include "selfsense/drivers/registry/registry.hpp"
#include "support/config_edits.hpp"

namespace selfsense::daemon {
namespace {

const std::filesystem::path kConfigDir = test::shipped_config_dir();

// sim.yaml shows every key of the daemon's own; the loader also asks for the absent ones.
DaemonConfig load_shipped(const char* name, std::set<std::string>* known = nullptr) {
  drivers::Registry registry;
  ConfigResult r = load_config(kConfigDir / name, &registry);
  EXPECT_TRUE(r.ok()) << name << ": " << (r.problems.empty() ? "" : r.problems.front());
  if (known != nullptr) known->insert(r.known_keys.begin(), r.known_keys.end());
  return r.config;
}

// A section the loader opens ("loop", "control.position") has no row of its own: its keys do.
bool is_section_of_rows(const std::string& key) {
  return std::ranges::any_of(reload_keys(), [&](const ReloadKey& row) {
    return row.key.starts_with(key + ".") || row.key.starts_with(key + "[");
  });
}

TEST(ReloadKeys, EveryKeyTheLoaderKnowsHasAReloadClass) {
  std::set<std::string> known;
  for (const char* name : {"sim.yaml", "selfsensed.yaml", "damping-sim.yaml", "can-sim.yaml",
                           "modbus-sim.yaml", "spi-ads131m04.yaml"}) {
    static_cast<void>(load_shipped(name, &known));
  }
  ASSERT_GT(known.size(), 50U);
  for (const std::string& key : known) {
    EXPECT_TRUE(find_reload_key(key) != nullptr || is_section_of_rows(key))
        << key << ": a configuration key without a reload class (live, when disarmed or refused) "
        << "in src/daemon/reload_keys.cpp";
  }
  // Every row is a key the loader knows (sim.yaml opens every section).
  for (const ReloadKey& row : reload_keys()) {
    EXPECT_TRUE(std::ranges::any_of(
        known, [&](const std::string& key) { return find_reload_key(key) == &row; }))
        << row.key << ": a row of no key the loader knows";
  }
}

TEST(ReloadKeys, RowsAreUniqueAndRefusedOnesCompare) {
  std::set<std::string_view> keys;
  for (const ReloadKey& row : reload_keys()) {
    EXPECT_TRUE(keys.insert(row.key).second) << row.key;
    EXPECT_EQ(row.changed != nullptr, row.reload == Reload::kRefused) << row.key;
  }
  EXPECT_EQ(find_reload_key("control.filters[1].type")->key, "control.filters");
  EXPECT_EQ(find_reload_key("driver.plant")->key, "driver");
  EXPECT_EQ(find_reload_key("driver.type")->key, "driver.type");
  EXPECT_EQ(find_reload_key("loop.rate_hz_x"), nullptr);
  EXPECT_EQ(find_reload_key("telemetry"), nullptr);
}

TEST(ReloadKeys, ChangedRefusedKeysAreNamedAndLiveOnesAreNot) {
  const DaemonConfig running = load_shipped("sim.yaml");
  EXPECT_TRUE(refused_changes(running, running).empty());

  DaemonConfig next = running;
  next.control.position.gains.kp *= 2.0;
  next.control.force.gains.ki *= 2.0;
  next.control.command_max /= 2.0;
  next.control.filter_count = 1;
  next.model = "other.yaml";
  EXPECT_TRUE(refused_changes(running, next).empty());

  next.loop.cpu_dma_latency_us = 20;
  next.control.position.tracking_time = 2e-3;
  next.safety.overrun.window = 5;
  next.socket.group = "selfsense";
  EXPECT_EQ(refused_changes(running, next),
            (std::vector<std::string>{"loop.cpu_dma_latency_us", "control.position.tracking_time_s",
                                      "safety.overrun.window_cycles", "socket.group"}));

  DaemonConfig driver = running;
  driver.driver_section += "\nrate: 2";
  EXPECT_EQ(refused_changes(running, driver), (std::vector<std::string>{"driver"}));
  driver.driver_type = "can";
  EXPECT_EQ(refused_changes(running, driver), (std::vector<std::string>{"driver.type"}));
}

}  // namespace
}  // namespace selfsense::daemon
