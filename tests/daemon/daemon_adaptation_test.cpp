// The online adaptation in the real selfsensed (docs/daemon.md, "Adaptation"), on the simulated
// transducer warming while the daemon runs (driver.temperature): the control socket freezes,
// resumes and shows the drift estimate through the loop's command ring; `status` and the
// Prometheus file show it; the model_state file keeps the adapted reconstruction's state
// (`reconstruction: adapted`), a restart resumes the learned drift, and each reconstruction
// refuses the other's state by name.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "daemon/recording_support.hpp"
#include "daemon/running_daemon.hpp"
#include "daemon/warming_support.hpp"
#include "selfsense/daemon/model_state_file.hpp"

namespace selfsense::daemon {
namespace {

using testing::adaptation_of;
using testing::play_sine;
using testing::RunningDaemon;
using testing::warming_config;

TEST(DaemonAdaptation, TheSocketFreezesAndResumesItAndARestartResumesTheLearnedDrift) {
  const testing::ScratchDir dir("daemon-adaptation");
  static_cast<void>(testing::copy_shipped_model(dir.path()));
  const std::filesystem::path state = dir.path() / "state.yaml";
  const std::filesystem::path config = dir.path() / "selfsensed.yaml";
  const std::string model_line = "model: " + (dir.path() / "model.yaml").string();
  const std::pair<std::string, std::string> keep_state{
      model_line, model_line + "\nmodel_state: " + state.string()};
  testing::write_text(config, warming_config(dir.path(), true, 4.0, {keep_state}));
  const auto start = [&] {
    return std::make_unique<RunningDaemon>(config, dir.path() / "control.sock",
                                           dir.path() / "selfsensed.log");
  };

  // The status once the loop has published its first adaptation snapshot (right after the
  // start the reply may precede it: the updates are then absent).
  const auto adapted_status = [](RunningDaemon& daemon) {
    nlohmann::json s = daemon.status();
    for (int i = 0; i < 100 && !s["adaptation"].contains("updates"); ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      s = daemon.status();
    }
    return s;
  };

  double saved_updates = 0.0;
  {
    const auto daemon = start();
    play_sine(*daemon);
    std::this_thread::sleep_for(std::chrono::seconds(4));
    const nlohmann::json status = daemon->status()["adaptation"];
    EXPECT_TRUE(status.value("enabled", false)) << status.dump();
    EXPECT_FALSE(status.value("frozen", true));
    EXPECT_GT(status.value("updates", 0), 100) << status.dump();
    EXPECT_GT(status.value("temperature_degc", 0.0), 30.0) << status.dump();
    EXPECT_GT(status.value("permittivity_change", 0.0), 0.0) << status.dump();

    const nlohmann::json frozen = daemon->request(R"({"request": "adapt", "action": "freeze"})");
    ASSERT_TRUE(frozen.value("ok", false)) << frozen.dump();
    EXPECT_TRUE(frozen.value("frozen", false));
    std::this_thread::sleep_for(std::chrono::milliseconds(300));  // a status period at least
    const nlohmann::json held = adaptation_of(*daemon);
    EXPECT_TRUE(held.value("frozen", false)) << held.dump();
    std::this_thread::sleep_for(std::chrono::milliseconds(700));
    EXPECT_EQ(adaptation_of(*daemon)["updates"], held["updates"]);  // the sine plays on

    const nlohmann::json resumed = daemon->request(R"({"request": "adapt", "action": "resume"})");
    ASSERT_TRUE(resumed.value("ok", false)) << resumed.dump();
    std::this_thread::sleep_for(std::chrono::milliseconds(700));
    const nlohmann::json learning = adaptation_of(*daemon);
    EXPECT_FALSE(learning.value("frozen", true));
    EXPECT_GT(learning.value("updates", 0), held.value("updates", 0));

    std::this_thread::sleep_for(std::chrono::milliseconds(1200));  // a telemetry period
    const std::string prom = testing::read_text(dir.path() / "selfsensed.prom");
    for (const char* metric :
         {"selfsense_adaptation_permittivity_change ", "selfsense_adaptation_loop_change ",
          "selfsense_adaptation_temperature_celsius ", "selfsense_adaptation_frozen 0",
          "selfsense_adaptation_updates_total "}) {
      EXPECT_NE(prom.find(metric), std::string::npos) << metric << "\n" << prom;
    }
    EXPECT_EQ(daemon->terminate(), 0);
  }
  StateOf of = StateOf::kPlain;
  const models::SavedState at_stop = read_model_state(state, &of);
  EXPECT_EQ(of, StateOf::kAdapted);
  ASSERT_FALSE(at_stop.values.empty());
  saved_updates = at_stop.values.back();  // the estimator's state ends with its update count
  EXPECT_GT(saved_updates, 100.0);

  {
    const auto daemon = start();
    const nlohmann::json s = adapted_status(*daemon);
    ASSERT_TRUE(s["adaptation"].contains("updates")) << s.dump();
    EXPECT_EQ(s["model"]["state_at_start"], "restored") << s.dump();
    // The learned drift goes on from the saved one (no sine: nothing new is learned).
    EXPECT_EQ(s["adaptation"]["updates"].get<double>(), saved_updates) << s.dump();
    EXPECT_GT(s["adaptation"]["temperature_degc"].get<double>(), 30.0) << s.dump();
    EXPECT_EQ(daemon->terminate(), 0);
  }

  // The plain reconstruction refuses the adapted state by name, and the socket says that
  // adaptation is off.
  testing::write_text(config, warming_config(dir.path(), false, 4.0, {keep_state}));
  {
    const auto daemon = start();
    EXPECT_EQ(daemon->status()["model"]["state_at_start"],
              "not restored: " + state.string() +
                  ": written by the adapted reconstruction, the daemon runs the plain one "
                  "(adaptation.enabled)");
    EXPECT_EQ(daemon->status()["adaptation"], nlohmann::json({{"enabled", false}}));
    const nlohmann::json off = daemon->request(R"({"request": "adapt", "action": "freeze"})");
    EXPECT_FALSE(off.value("ok", true));
    EXPECT_NE(off.value("error", "").find("adapt: adaptation is off"), std::string::npos)
        << off.dump();
    EXPECT_EQ(daemon->terminate(), 0);
  }
  // ... and the adapted one the plain state.
  testing::write_text(config, warming_config(dir.path(), true, 4.0, {keep_state}));
  {
    const auto daemon = start();
    EXPECT_EQ(daemon->status()["model"]["state_at_start"],
              "not restored: " + state.string() +
                  ": written by the plain reconstruction, the daemon runs the adapted one "
                  "(adaptation.enabled)");
    EXPECT_EQ(adapted_status(*daemon)["adaptation"]["updates"], 0);
    EXPECT_EQ(daemon->terminate(), 0);
  }
}

}  // namespace
}  // namespace selfsense::daemon
