// The real selfsensed for tests that crash, signal and reload it: a scratch configuration
// derived from config/sim.yaml (the shipped example, so the test follows it), and the process
// (support/daemon_process.hpp) with requests over its control socket.
#pragma once

#include <signal.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "daemon/recording_support.hpp"
#include "selfsense/daemon/control_client.hpp"
#include "support/config_edits.hpp"
#include "support/daemon_process.hpp"
#include "support/sanitizers.hpp"

namespace selfsense::daemon::testing {

// A copy of the shipped model (config/models/sim.yaml) as dir/model.yaml, which scratch_config
// names; returns its path.
inline std::filesystem::path copy_shipped_model(const std::filesystem::path& dir) {
  std::filesystem::path model = dir / "model.yaml";
  write_text(model, read_text(std::filesystem::path(SELFSENSE_SOURCE_DIR) / "config" / "models" /
                              "sim.yaml"));
  return model;
}

// The loop rate of the process tests' daemon: config/sim.yaml's 10 kHz, 5 kHz under
// AddressSanitizer. These tests check what the daemon does (reload, stop, state, crash), not its
// timing (the Release run, the soak and loop_timing_bench do). Under ASan the cycle takes several
// times longer (p99 33-65 us with the shipped model and the libraries at -O1), and on a loaded
// 2-core machine runs of 64 late cycles, the most the overrun policy then allowed, faulted a
// reload test at 10 kHz (config/sim.yaml now faults only on a 0.2 s stall).
inline constexpr double kProcessTestRate = test::kAddressSanitizer ? 5000.0 : 10000.0;

inline std::vector<std::pair<std::string, std::string>> rate_for_this_build() {
  if (kProcessTestRate == 10000.0) return {};
  return {{"rate_hz: 10000", "rate_hz: " + std::to_string(static_cast<int>(kProcessTestRate))},
          // below 0.45 of the rate
          {"{type: low-pass, frequency_hz: 3000.0}", "{type: low-pass, frequency_hz: 2200.0}"}};
}

// config/sim.yaml with the model, socket and telemetry in `dir`, the recordings in `recordings`
// (default dir/recordings), the loop rate for this build, and the replacements given (each
// `from` must occur: a changed example fails the test loudly).
inline std::string scratch_config(const std::filesystem::path& dir,
                                  const std::vector<std::pair<std::string, std::string>>& changes,
                                  std::filesystem::path recordings = {}) {
  if (recordings.empty()) recordings = dir / "recordings";
  const std::filesystem::path source = SELFSENSE_SOURCE_DIR;
  std::string text = read_text(source / "config" / "sim.yaml");
  std::vector<std::pair<std::string, std::string>> all = {
      {"model: models/sim.yaml", "model: " + (dir / "model.yaml").string()},
      {"plant: plant/daemon.yaml",
       "plant: " + (source / "config" / "plant" / "daemon.yaml").string()},
      {"directory: ../build/sim/recordings", "directory: " + recordings.string()},
      {"path: ../build/sim/control.sock", "path: " + (dir / "control.sock").string()},
      {"prometheus_file: ../build/sim/selfsensed.prom",
       "prometheus_file: " + (dir / "selfsensed.prom").string()},
  };
  const auto rate = rate_for_this_build();
  all.insert(all.end(), rate.begin(), rate.end());
  all.insert(all.end(), changes.begin(), changes.end());
  return test::edited(std::move(text), all, "config/sim.yaml");
}

// selfsensed started (test::DaemonProcess) and answering on its control socket.
class RunningDaemon final {
 public:
  // Starts selfsensed --config `config`; output to `log`.out and .err. Waits until its socket
  // answers.
  RunningDaemon(const std::filesystem::path& config, std::filesystem::path socket,
                const std::filesystem::path& log)
      : socket_(std::move(socket)),
        err_(log.string() + ".err"),
        process_(SELFSENSED_BINARY, config, log) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (std::chrono::steady_clock::now() < deadline) {
      if (process_.wait(std::chrono::milliseconds(0))) {
        throw std::runtime_error("selfsensed exited at start: " + read_text(err_));
      }
      try {
        if (status().value("ok", false)) return;
      } catch (const ControlClientError&) {
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    throw std::runtime_error("selfsensed did not answer within 30 s: " + read_text(err_));
  }

  // One request line; the parsed reply. Throws ControlClientError when the socket fails.
  nlohmann::json request(const std::string& line) {
    ControlClient client(socket_, std::chrono::milliseconds(3000));
    return nlohmann::json::parse(client.exchange(line));
  }
  nlohmann::json status() { return request(R"({"request": "status"})"); }
  // Reset from the power-up fault (retried while its cause still holds, up to 2 s), then arm;
  // false if either is refused.
  bool reset_and_arm() {
    bool reset = false;
    for (int i = 0; i < 100 && !reset; ++i) {
      reset = request(R"({"request": "reset"})").value("ok", false);
      if (!reset) std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return reset && request(R"({"request": "arm"})").value("ok", false);
  }

  void signal(int sig) const { process_.signal(sig); }
  // kill -9; the exit status as test::DaemonProcess::wait gives it (128 + 9).
  int kill_hard() {
    process_.signal(SIGKILL);
    return process_.wait(std::chrono::seconds(10)).value_or(-1);
  }
  // SIGTERM; the exit status (-1: none within 10 s).
  int terminate() {
    process_.signal(SIGTERM);
    return process_.wait(std::chrono::seconds(10)).value_or(-1);
  }
  // What it wrote to stderr so far.
  [[nodiscard]] std::string log() const { return read_text(err_); }

 private:
  std::filesystem::path socket_;
  std::filesystem::path err_;
  test::DaemonProcess process_;
};

}  // namespace selfsense::daemon::testing
