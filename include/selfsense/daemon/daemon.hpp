// selfsensed, assembled: the driver, the model, the control law and the supervisor in the
// real-time loop (runtime::LoopRunner), the recorder's writer thread, the control socket and
// the main thread, which handles signals, systemd notification and telemetry. Not real-time
// code; the loop thread is the only real-time one.
//
// Signals (blocked in every thread, taken by the main thread with sigtimedwait):
//   SIGTERM, SIGINT   disarm (the loop writes the safe output from the next cycle), stop the
//                     loop, drive the amplifier to its safe output (driver deactivate), flush and
//                     close the recorder, STOPPING=1, exit 0
//   SIGHUP            reload (reload() below)
// systemd (Type=notify): READY=1 once the loop runs, STATUS= every second, WATCHDOG=1 only while
// the loop makes progress (a stalled loop gets the service restarted), STOPPING=1.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "selfsense/daemon/config.hpp"
#include "selfsense/daemon/control_handler.hpp"
#include "selfsense/daemon/control_server.hpp"
#include "selfsense/daemon/model_state_file.hpp"
#include "selfsense/daemon/recorder.hpp"
#include "selfsense/models/model_identity.hpp"
#include "selfsense/runtime/driver.hpp"
#include "selfsense/runtime/loop.hpp"
#include "selfsense/runtime/loop_runner.hpp"
#include "selfsense/runtime/pacer.hpp"

namespace selfsense::daemon {

// What a reload did. When problems is not empty nothing changed.
struct ReloadResult {
  std::vector<std::string> problems{};  // one line each, naming the file and the key
  bool tuning{false};                   // gains, filters and command limits were applied
  bool model{false};                    // a new model runs
  [[nodiscard]] bool ok() const noexcept { return problems.empty(); }
};

// The parameters a reload can change, as they run now.
struct RunningParameters {
  std::filesystem::path model{};
  std::uint64_t model_hash{0};  // models::parameter_hash (models/model_identity.hpp)
  control::Pid::Gains position{};
  control::Pid::Gains force{};
  std::vector<FilterSection> filters{};
  double command_min{0.0};  // E [V/m]
  double command_max{0.0};
};

class Daemon final {
 public:
  // Builds everything (loads the model, configures and activates the driver, prepares the
  // recorder); throws std::runtime_error naming what failed. Starts no thread. The driver
  // section reader (the driver registry) reads the driver's keys again on reload; it must
  // outlive the daemon.
  Daemon(DaemonConfig config, std::unique_ptr<runtime::Driver> driver,
         DriverSectionReader& driver_reader);
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;
  Daemon(Daemon&&) = delete;
  Daemon& operator=(Daemon&&) = delete;
  ~Daemon();

  // Runs until SIGTERM or SIGINT; returns the exit status. Call from the main thread with
  // SIGTERM, SIGINT and SIGHUP blocked (block_signals() before any thread starts).
  int run();
  static void block_signals();

  // For the control handler (any non-real-time thread).
  // Sends a command and waits for the loop's answer (nullopt on timeout). *submitted says
  // whether it reached the loop's ring (then objects it points to belong to the loop).
  std::optional<runtime::LoopAnswer> command(runtime::LoopCommand c,
                                             std::chrono::milliseconds timeout,
                                             bool* submitted = nullptr);
  [[nodiscard]] runtime::StatusSnapshot status() const noexcept { return loop_->status(); }
  [[nodiscard]] const DaemonConfig& config() const noexcept { return config_; }
  [[nodiscard]] Recorder& recorder() noexcept { return *recorder_; }
  [[nodiscard]] const runtime::Driver& driver() const noexcept { return *driver_; }
  // The driver's bench force input, or null (runtime::ForceInput: thread-safe).
  [[nodiscard]] runtime::ForceInput* force_input() noexcept { return driver_->force_input(); }
  // Real-time set-up problems; arming is refused while any exists unless degraded timing is
  // allowed by the configuration.
  [[nodiscard]] const runtime::RtSetupResult& rt_setup() const noexcept { return rt_setup_; }
  [[nodiscard]] bool degraded_timing() const noexcept { return !rt_setup_.complete(); }
  [[nodiscard]] bool may_arm() const noexcept {
    return rt_setup_.complete() || config_.loop.allow_degraded_timing;
  }
  // Reads the configuration file and the model file again; all or nothing. Applied while armed:
  // the PID gains, the filter chain (control.filters, control::FilterChain::assign) and the
  // command limits (control.command_v_per_m), in one cycle (runtime::Controller::tune). Applied
  // while disarmed: a model whose content changed (the same file rewritten, or another path),
  // with the feedforward's inverse built from it; its memory is carried over
  // (runtime_model.hpp, adopt_state); not while adaptation is enabled (the learned drift is
  // relative to the running model: a restart). Any other changed key, a file that does not
  // load (half-written: a YAML or model error naming file and line) or a model change while
  // armed is refused by name and the running parameters stay.
  ReloadResult reload();
  // What runs now (any thread; a reload changes it).
  [[nodiscard]] RunningParameters parameters() const;
  // The model's memory (model_state_file.hpp), copied by the loop at a cycle boundary into
  // recorder.directory/model-state-UTC-cycleN.yaml: a dump to look at or to copy to a
  // model_state file. The file's path, or an error naming what failed.
  struct StateSaved {
    std::filesystem::path path{};
    std::string error{};
  };
  StateSaved dump_model_state();
  // The configured model_state file is written at a clean stop and taken (read, then removed)
  // at the next start, so a crash leaves none. What happened to it at start: "restored",
  // "none" (no file), "not restored: WHY", or "off" (no model_state configured).
  [[nodiscard]] const std::string& model_state_at_start() const noexcept { return state_at_start_; }
  // The health estimate's state travels in the same file (its `health` key): "restored",
  // "none" (no file, or one without it), "not restored: WHY" (the model's state was not
  // restored, or its size differs), or "off" (health or model_state not configured).
  [[nodiscard]] const std::string& health_state_at_start() const noexcept {
    return health_at_start_;
  }
  // Test hook for the watchdog: the loop stops making progress.
  void stall_loop(bool on) noexcept { runner_->stall(on); }
  void request_stop() noexcept { stop_requested_.store(true); }

 private:
  class Sink;
  void free_retired();
  // Restores the model_state file through `restore` when `running` wrote it.
  void restore_model_state(
      StateOf running,
      const std::function<models::RestoreResult(const models::SavedState&)>& restore);
  StateSaved save_model_state(const std::filesystem::path& path);
  // The health state read with the model's, into the loop before it runs (health_at_start_).
  void resume_health();
  void notify_status();
  void write_telemetry();

  DaemonConfig config_;
  DriverSectionReader* driver_reader_;
  std::unique_ptr<runtime::Driver> driver_;
  std::unique_ptr<Recorder> recorder_;
  std::unique_ptr<Sink> sink_;
  runtime::SteadyClock clock_{};
  std::unique_ptr<runtime::Loop> loop_;
  std::unique_ptr<runtime::LoopRunner> runner_;
  std::unique_ptr<ControlHandler> handler_;
  std::unique_ptr<ControlServer> server_;
  runtime::RtSetupResult rt_setup_{};
  std::mutex command_mutex_{};  // one producer and one answer reader at a time
  std::uint64_t next_id_{0};
  std::atomic<bool> stop_requested_{false};
  std::string model_text_{};  // the running model as models::model_to_string writes it
  std::uint64_t model_hash_{0};
  mutable std::mutex parameters_mutex_{};  // config_.model, model_hash_, the gains: reload writes
  std::mutex state_mutex_{};               // state_buffer_: the loop writes it while one waits
  models::SavedState state_buffer_{};      // sized for the running model
  StateOf state_of_{StateOf::kPlain};      // the running reconstruction (adaptation.enabled)
  std::string state_at_start_{"off"};
  std::vector<double> health_buffer_{};  // Loop::health_state_size(); the loop writes it too
  std::vector<double> health_read_{};    // the file's `health` values, until the loop takes them
  std::string health_at_start_{"off"};
};

}  // namespace selfsense::daemon
