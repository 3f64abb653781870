// The health estimate across a restart of the real selfsensed (docs/health.md, "The daemon"):
// its state (baseline, trends, counts, latched warnings with their raise times) is written with
// the model's into the model_state file at a clean stop (`health` key) and resumed at the next
// start (status health.state_at_start), so the baseline the depolarisation alarm compares with
// is kept, and a warning latched before the stop is still latched, raised at the same time.
// The warming stack of the adaptation tests (25 -> 45 degC over 4 s, a 2 Hz sine), with a
// baseline that is ready in seconds and an overheating band it crosses.
#include <gtest/gtest.h>

#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "daemon/recording_support.hpp"
#include "daemon/running_daemon.hpp"
#include "daemon/warming_support.hpp"
#include "selfsense/adaptation/health_alarms.hpp"
#include "selfsense/adaptation/health_estimator.hpp"
#include "selfsense/daemon/model_state_file.hpp"

namespace selfsense::daemon {
namespace {

using testing::play_sine;
using testing::RunningDaemon;
using testing::warming_config;

// Where the figures sit in the saved health values (HealthEstimator::save_state, then
// HealthAlarms::save_state).
constexpr std::size_t kSamples = 0;
constexpr std::size_t kBaselineCycles = 3;
constexpr std::size_t kCycles = 8;
constexpr std::size_t kCompared = 9;
constexpr std::size_t kAlarms = adaptation::HealthEstimator::kStateSize;
constexpr std::size_t kOverheatingRaised =
    kAlarms + 1 + static_cast<std::size_t>(adaptation::HealthAlarm::kOverheating);

TEST(DaemonHealthState, ARestartResumesTheBaselineTrendsAndLatchedWarnings) {
  const testing::ScratchDir dir("daemon-health-state");
  static_cast<void>(testing::copy_shipped_model(dir.path()));
  const std::filesystem::path state = dir.path() / "state.yaml";
  const std::filesystem::path config = dir.path() / "selfsensed.yaml";
  const std::string model_line = "model: " + (dir.path() / "model.yaml").string();
  testing::write_text(config,
                      warming_config(dir.path(), true, 4.0,
                                     {{model_line, model_line + "\nmodel_state: " + state.string()},
                                      {"health:\n  enabled: false", "health:\n  enabled: true"},
                                      {"max_temperature_degc: 80.0", "max_temperature_degc: 28.0"},
                                      {"settle_s: 100.0", "settle_s: 1.0"},
                                      {"baseline_cycles: 20", "baseline_cycles: 4"}}));
  const auto start = [&] {
    return std::make_unique<RunningDaemon>(config, dir.path() / "control.sock",
                                           dir.path() / "selfsensed.log");
  };
  // The health figures once the loop has published its first snapshot (the socket answers
  // before that; on a loaded machine the first status can come first).
  const auto published_health = [](RunningDaemon& daemon) {
    nlohmann::json h = daemon.status()["health"];
    for (int i = 0; i < 100 && !h.contains("cycles"); ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      h = daemon.status()["health"];
    }
    return h;
  };

  nlohmann::json before;
  {
    const auto daemon = start();
    // Configured: on from the first answer, whether or not the loop has published yet.
    EXPECT_TRUE(daemon->status()["health"].value("enabled", false));
    EXPECT_EQ(published_health(*daemon)["state_at_start"], "none");
    play_sine(*daemon);
    for (int i = 0; i < 100; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      before = daemon->status()["health"];
      if (before.value("compared_cycles", 0) >= 2 &&
          before["alarms"]["overheating"].value("latched", false)) {
        break;
      }
    }
    ASSERT_TRUE(before.value("baseline_ready", false)) << before.dump();
    ASSERT_TRUE(before["alarms"]["overheating"].value("latched", false)) << before.dump();
    EXPECT_EQ(daemon->terminate(), 0);
  }
  std::vector<double> at_stop;
  static_cast<void>(read_model_state(state, nullptr, &at_stop));
  ASSERT_EQ(at_stop.size(), runtime::Loop::kHealthStateSize);
  EXPECT_EQ(at_stop[kBaselineCycles], 4.0);
  EXPECT_GE(at_stop[kCompared], before["compared_cycles"].get<double>());
  EXPECT_GE(at_stop[kOverheatingRaised], 0.0);

  {
    const auto daemon = start();
    const nlohmann::json h = published_health(*daemon);
    EXPECT_EQ(h["state_at_start"], "restored") << h.dump();
    EXPECT_TRUE(h.value("baseline_ready", false)) << h.dump();
    EXPECT_EQ(h["cycles"].get<double>(), at_stop[kCycles]) << h.dump();
    EXPECT_EQ(h["compared_cycles"].get<double>(), at_stop[kCompared]) << h.dump();
    EXPECT_TRUE(h["alarms"]["overheating"].value("latched", false)) << h.dump();
    EXPECT_EQ(h["alarms"]["overheating"]["raised_at_s"].get<double>(), at_stop[kOverheatingRaised])
        << h.dump();
    // Saved again without a drive (ready: no cycle, no hold at zero field): the same values,
    // bit for bit, but for the sample count, which went on.
    const nlohmann::json saved = daemon->request(R"({"request": "state", "action": "save"})");
    ASSERT_TRUE(saved.value("ok", false)) << saved.dump();
    std::vector<double> again;
    static_cast<void>(read_model_state(saved["path"].get<std::string>(), nullptr, &again));
    ASSERT_EQ(again.size(), at_stop.size());
    EXPECT_GE(again[kSamples], at_stop[kSamples]);
    for (std::size_t i = 1; i < again.size(); ++i)
      EXPECT_EQ(again[i], at_stop[i]) << "health value " << i;
    EXPECT_EQ(daemon->terminate(), 0);
  }

  // Without health the daemon writes no health key, and a later start with health says so.
  testing::write_text(
      config, warming_config(dir.path(), true, 4.0,
                             {{model_line, model_line + "\nmodel_state: " + state.string()}}));
  {
    const auto daemon = start();
    EXPECT_EQ(daemon->status()["health"], nlohmann::json({{"enabled", false}}));
    EXPECT_EQ(daemon->terminate(), 0);
  }
  std::vector<double> none{1.0};
  static_cast<void>(read_model_state(state, nullptr, &none));
  EXPECT_TRUE(none.empty());
}

}  // namespace
}  // namespace selfsense::daemon
