// The model's memory across restarts: the real selfsensed writes it into its model_state file at
// a clean stop and the next start takes it (status model.state_at_start; the file is removed so
// that a crash leaves none), so the estimate goes on from the actuator's history; a state written
// by another model is not restored, and says so. On request it dumps the memory into the
// recorder's directory.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <string>
#include <thread>

#include "daemon/recording_support.hpp"
#include "daemon/running_daemon.hpp"
#include "selfsense/daemon/model_state_file.hpp"
#include "selfsense/model_io/model_yaml.hpp"

namespace selfsense::daemon {
namespace {

using testing::RunningDaemon;

TEST(DaemonState, TheModelsMemoryIsSavedAtAStopAndRestoredAtTheNextStart) {
  const testing::ScratchDir dir("daemon-state");
  const std::filesystem::path model = testing::copy_shipped_model(dir.path());
  const std::filesystem::path state = dir.path() / "state.yaml";
  const std::filesystem::path config = dir.path() / "selfsensed.yaml";
  testing::write_text(
      config, testing::scratch_config(
                  dir.path(), {{"model: " + model.string(),
                                "model: " + model.string() + "\nmodel_state: " + state.string()}}));
  const auto start = [&] {
    return std::make_unique<RunningDaemon>(config, dir.path() / "control.sock",
                                           dir.path() / "selfsensed.log");
  };

  models::SavedState on_request;
  {
    const auto daemon = start();
    EXPECT_EQ(daemon->status()["model"]["state_at_start"], "none");
    const nlohmann::json saved = daemon->request(R"({"request": "state", "action": "save"})");
    ASSERT_TRUE(saved.value("ok", false)) << saved.dump();
    const std::filesystem::path dump = saved["path"].get<std::string>();
    EXPECT_EQ(dump.parent_path(), dir.path() / "recordings");
    EXPECT_EQ(dump.filename().string().rfind("model-state-", 0), 0U) << dump;
    on_request = read_model_state(dump);
    EXPECT_FALSE(std::filesystem::exists(state));  // written at the stop only
    // Through a large excursion, then a stop: the memory at the stop is saved.
    ASSERT_TRUE(daemon->reset_and_arm()) << daemon->status().dump();
    ASSERT_TRUE(daemon->request(R"({"request": "setpoint", "value": 1.2e-3})").value("ok", false));
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    EXPECT_EQ(daemon->terminate(), 0);
  }
  const models::SavedState at_stop = read_model_state(state);
  EXPECT_EQ(at_stop.identity, on_request.identity);
  EXPECT_NE(at_stop.values, on_request.values);

  {
    const auto daemon = start();
    const nlohmann::json s = daemon->status();
    EXPECT_EQ(s["model"]["state_at_start"], "restored") << s.dump();
    EXPECT_FALSE(std::filesystem::exists(state));  // taken: a crash now would leave none
    EXPECT_EQ(daemon->kill_hard(), 128 + 9);
  }
  {
    const auto daemon = start();
    EXPECT_EQ(daemon->status()["model"]["state_at_start"], "none");
    EXPECT_EQ(daemon->terminate(), 0);
  }

  // A re-identified model: the saved memory is not its own and is left alone.
  models::TransducerModel next = models::load_model(model);
  next.actuator->offset += 2e-6;
  models::save_model(next, model);
  {
    const auto daemon = start();
    const std::string note = daemon->status()["model"]["state_at_start"];
    EXPECT_EQ(note, "not restored: " + state.string() + ": written by another model");
    EXPECT_EQ(daemon->terminate(), 0);
  }
  EXPECT_NE(read_model_state(state).identity, at_stop.identity);  // the new model's, at its stop
}

}  // namespace
}  // namespace selfsense::daemon
