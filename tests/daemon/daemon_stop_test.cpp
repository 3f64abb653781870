// SIGTERM while armed: the real selfsensed ramps the command down to the safe output over
// safety.stop_ramp_s instead of stepping it (a step rings the mount and pulls the stack into
// tension), then disarms, flushes its recording and exits 0. Read back from its own recording.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <thread>

#include "daemon/recording_support.hpp"
#include "daemon/running_daemon.hpp"
#include "selfsense/io/recording.hpp"

namespace selfsense::daemon {
namespace {

using testing::RunningDaemon;

constexpr double kRate = testing::kProcessTestRate;
constexpr int kArmed = 2;  // the recording's state column (docs/recorder.md)

TEST(DaemonStop, SigtermWhileArmedRampsToTheSafeOutputThenExitsZero) {
  const testing::ScratchDir dir("daemon-stop");
  testing::copy_shipped_model(dir.path());
  const std::filesystem::path recordings = dir.path() / "recordings";
  const std::filesystem::path config = dir.path() / "selfsensed.yaml";
  testing::write_text(
      config, testing::scratch_config(
                  dir.path(), {{"record_at_start: false", "record_at_start: true"}}, recordings));
  {
    RunningDaemon daemon(config, dir.path() / "control.sock", dir.path() / "selfsensed.log");
    ASSERT_TRUE(daemon.reset_and_arm()) << daemon.status().dump();
    ASSERT_TRUE(daemon.request(R"({"request": "setpoint", "value": 8e-4})").value("ok", false));
    std::this_thread::sleep_for(std::chrono::milliseconds(600));
    EXPECT_EQ(daemon.terminate(), 0) << daemon.log();
  }
  const testing::ReadBack back = testing::read_back(recordings, "selfsensed");
  ASSERT_EQ(back.files.size(), 1U);
  const io::Recording r = io::read_recording_csv(back.files.front(), {{"command", "state"}});
  const auto command = r.column("command");
  const auto state = r.column("state");
  // The ramp's last cycle disarms: it is the first row not armed, and the n rows up to it are
  // the ramp (0.05 s, 500 cycles), from the controller's last command in the row before them.
  std::size_t end = state.size();
  while (end > 0 && state[end - 1] != kArmed)
    --end;
  const auto n = static_cast<std::size_t>(0.05 * kRate);
  ASSERT_GT(end, n + 10) << "never armed";
  ASSERT_LT(end, state.size()) << "no row after the ramp";
  const double from = command[end - n];
  ASSERT_GT(from, 5e5);
  for (std::size_t k = 1; k <= n; ++k) {
    const double expected = from * static_cast<double>(n - k) / static_cast<double>(n);
    ASSERT_NEAR(command[end - n + k], expected, 1e-9 * from) << "ramp cycle " << k;
  }
  for (std::size_t i = end; i < command.size(); ++i) {
    ASSERT_NE(state[i], kArmed) << "row " << i;
    ASSERT_EQ(command[i], 0.0) << "row " << i;
  }
}

}  // namespace
}  // namespace selfsense::daemon
