// A model or configuration file replaced while the real selfsensed runs is taken only on a
// reload, only when it is whole and valid, and a model only while disarmed: a half-written file
// is refused by name (through the socket and through SIGHUP) and the running model and gains
// stay; the valid one is then taken all at once and the loop tracks on the new model.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "daemon/recording_support.hpp"
#include "daemon/running_daemon.hpp"
#include "selfsense/model_io/model_yaml.hpp"

namespace selfsense::daemon {
namespace {

using testing::RunningDaemon;

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(DaemonReload, OnlyAWholeValidFileIsTakenAndAModelOnlyWhileDisarmed) {
  const testing::ScratchDir dir("daemon-reload");
  const std::filesystem::path model_path = testing::copy_shipped_model(dir.path());
  const std::filesystem::path config = dir.path() / "selfsensed.yaml";
  const std::string config_text = testing::scratch_config(dir.path(), {});
  testing::write_text(config, config_text);
  RunningDaemon daemon(config, dir.path() / "control.sock", dir.path() / "selfsensed.log");
  const auto reload = [&] { return daemon.request(R"({"request": "reload"})"); };
  const nlohmann::json start = daemon.status();
  const std::string hash0 = start["model"]["hash"];
  const double kp0 = start["gains"]["position"]["kp"];
  EXPECT_EQ(start["model"]["path"], model_path.string());
  const auto running_unchanged = [&] {
    const nlohmann::json s = daemon.status();
    EXPECT_EQ(s["model"]["hash"], hash0);
    EXPECT_EQ(s["gains"]["position"]["kp"], kp0);
    EXPECT_EQ(s["counters"]["model_swaps"], 0);
  };

  // The next model: the same stack with another strain offset (a re-identification).
  models::TransducerModel next = models::load_model(model_path);
  next.actuator->offset += 2e-6;
  const std::string next_text = models::model_to_string(next);

  // Half of it written over the running model's file: refused, naming the file.
  testing::write_text(model_path, next_text.substr(0, next_text.size() / 2));
  nlohmann::json r = reload();
  EXPECT_FALSE(r.value("ok", true)) << r.dump();
  EXPECT_TRUE(contains(r.value("error", ""), model_path.string() + ":")) << r.dump();
  running_unchanged();
  // Cut just before the end marker: valid YAML and a valid model, refused by the marker.
  testing::write_text(model_path, next_text.substr(0, next_text.find("complete: true")));
  r = reload();
  EXPECT_FALSE(r.value("ok", true)) << r.dump();
  EXPECT_TRUE(contains(r.value("error", ""), "complete")) << r.dump();
  running_unchanged();

  // The whole model, and half of a configuration with new gains: refused, naming the file.
  testing::write_text(model_path, next_text);
  std::string new_gains = config_text;
  new_gains.replace(new_gains.find("kp: 2.0e8"), 9, "kp: 1.5e8");
  testing::write_text(config, new_gains.substr(0, new_gains.find("safety:") + 12));
  r = reload();
  EXPECT_FALSE(r.value("ok", true)) << r.dump();
  EXPECT_TRUE(contains(r.value("error", ""), config.string() + ":")) << r.dump();
  running_unchanged();
  // Cut inside the new gain (kp: 1.5 is valid YAML): refused, the line is not finished.
  testing::write_text(config, new_gains.substr(0, new_gains.find("kp: 1.5e8") + 7));
  r = reload();
  EXPECT_FALSE(r.value("ok", true)) << r.dump();
  EXPECT_TRUE(contains(r.value("error", ""), "does not end with a line break")) << r.dump();
  running_unchanged();

  // Both whole, but armed: the model is refused and nothing changes (all or nothing).
  testing::write_text(config, new_gains);
  ASSERT_TRUE(daemon.reset_and_arm()) << daemon.status().dump();
  r = reload();
  EXPECT_FALSE(r.value("ok", true)) << r.dump();
  EXPECT_TRUE(contains(r.value("error", ""), "only while disarmed")) << r.dump();
  running_unchanged();

  // SIGHUP while disarmed with a half-written model: refused in the log, nothing changes.
  ASSERT_TRUE(daemon.request(R"({"request": "disarm"})").value("ok", false));
  // Cut after a whole line (a cut inside a line is refused by the YAML parser instead).
  testing::write_text(model_path,
                      next_text.substr(0, next_text.rfind('\n', next_text.size() / 3) + 1));
  daemon.signal(SIGHUP);
  for (int i = 0; i < 100 && !contains(daemon.log(), "reload refused: "); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_TRUE(contains(daemon.log(), "model: " + model_path.string() + ":1: complete: missing"))
      << daemon.log();
  running_unchanged();

  // Whole and disarmed: the model and the gains are taken together.
  testing::write_text(model_path, next_text);
  r = reload();
  ASSERT_TRUE(r.value("ok", false)) << r.dump();
  EXPECT_EQ(r["reloaded"], "gains, filters, limits, model");
  std::this_thread::sleep_for(std::chrono::milliseconds(100));  // status is published every 10 ms
  const nlohmann::json after = daemon.status();
  EXPECT_NE(after["model"]["hash"], hash0);
  EXPECT_EQ(after["gains"]["position"]["kp"], 1.5e8);
  EXPECT_EQ(after["counters"]["model_swaps"], 1);

  // The loop tracks on the new model.
  ASSERT_TRUE(daemon.request(R"({"request": "arm"})").value("ok", false));
  ASSERT_TRUE(daemon.request(R"({"request": "setpoint", "value": 8e-4})").value("ok", false));
  std::this_thread::sleep_for(std::chrono::milliseconds(600));
  const nlohmann::json tracking = daemon.status();
  EXPECT_EQ(tracking["state"], "armed") << tracking.dump();
  EXPECT_NEAR(tracking["estimate"]["S_hat"].get<double>(), 8e-4, 2e-5) << tracking.dump();
  EXPECT_EQ(daemon.terminate(), 0);
}

// While armed and tracking, a reload takes new filters (a notch moved, a section added) and a
// narrower command range in the next cycle: the command stays inside the new range and the loop
// stays armed. A changed key that cannot change while running is refused by name with the rest.
TEST(DaemonReload, FiltersAndCommandLimitsChangeWhileArmed) {
  const testing::ScratchDir dir("daemon-reload-tuning");
  const std::filesystem::path config = dir.path() / "selfsensed.yaml";
  testing::copy_shipped_model(dir.path());
  const std::string config_text = testing::scratch_config(dir.path(), {});
  testing::write_text(config, config_text);
  RunningDaemon daemon(config, dir.path() / "control.sock", dir.path() / "selfsensed.log");
  const nlohmann::json start = daemon.status();
  ASSERT_EQ(start["filters"].size(), 2U) << start.dump();
  EXPECT_EQ(start["filters"][0]["frequency_hz"], 2000.0);
  EXPECT_EQ(start["command_v_per_m"][1], 2.0e6);
  ASSERT_TRUE(daemon.reset_and_arm()) << daemon.status().dump();
  ASSERT_TRUE(daemon.request(R"({"request": "setpoint", "value": 1.0e-3})").value("ok", false));
  std::this_thread::sleep_for(std::chrono::milliseconds(400));
  const double command = daemon.status()["estimate"]["command"];
  ASSERT_GT(command, 1.0e6);  // the setpoint takes more than the new limit below

  // Refused with the change of a key that needs a restart: nothing changes.
  const auto with = [&](const std::vector<std::pair<std::string, std::string>>& edits) {
    std::string text = config_text;
    for (const auto& [from, to] : edits)
      text.replace(text.find(from), from.size(), to);
    return text;
  };
  const std::pair<std::string, std::string> narrower{"command_v_per_m: [0.0, 2.0e6]",
                                                     "command_v_per_m: [0.0, 1.0e6]"};
  const std::pair<std::string, std::string> new_filters{
      "- {type: notch, frequency_hz: 2000.0,",
      "- {type: low-pass-1, frequency_hz: 2100.0}\n    - {type: notch, frequency_hz: 1800.0,"};
  testing::write_text(config, with({narrower, new_filters, {"priority: 80", "priority: 70"}}));
  nlohmann::json r = daemon.request(R"({"request": "reload"})");
  EXPECT_FALSE(r.value("ok", true)) << r.dump();
  EXPECT_TRUE(contains(r.value("error", ""), "loop.priority: cannot change while running"))
      << r.dump();
  EXPECT_EQ(daemon.status()["command_v_per_m"][1], 2.0e6);

  testing::write_text(config, with({narrower, new_filters}));
  r = daemon.request(R"({"request": "reload"})");
  ASSERT_TRUE(r.value("ok", false)) << r.dump();
  EXPECT_EQ(r["reloaded"], "gains, filters, limits");
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const nlohmann::json after = daemon.status();
  EXPECT_EQ(after["state"], "armed") << after.dump();
  EXPECT_EQ(after["command_v_per_m"][1], 1.0e6);
  ASSERT_EQ(after["filters"].size(), 3U) << after.dump();
  EXPECT_EQ(after["filters"][0]["type"], "low-pass-1");
  EXPECT_EQ(after["filters"][1]["frequency_hz"], 1800.0);
  EXPECT_LE(after["estimate"]["command"].get<double>(), 1.0e6) << after.dump();
  EXPECT_GE(after["estimate"]["command"].get<double>(), 0.99e6) << after.dump();  // saturated
  EXPECT_EQ(daemon.terminate(), 0);
}

}  // namespace
}  // namespace selfsense::daemon
