// The real-time loop, one explicit cycle:
//
//   commands -> read E, D (driver) -> reconstruct T_hat, S_hat (model) -> supervise
//            -> setpoint (hold, socket, wave) -> control -> write the command (driver) -> record
//
// Safety (supervisor.hpp): a driver error, timeout or stale sample, a rejected or failed
// reconstruction, an estimate outside the configured physical range, the overrun policy and the
// setpoint watchdog each latch a fault; the command written in the same cycle is then the safe
// output (zero or hold, configured). While faulted or ready the safe output is written too.
// A ramped stop (CommandKind::kRampDown over n cycles) writes, in its k-th cycle (k = 1..n),
//   E[k] = E_safe + (E_0 - E_safe) (n - k) / n       (E_0: the last command before it)
// with the controller left out, and disarms after the n-th: the stack is brought to the safe
// output slower than its mount rings.
//
// Adaptation (the second constructor): the reconstruction is adaptation::AdaptedReconstruction,
// which learns the permittivity drift from E and D (docs/adaptation.md). It learns nothing
// from a sample the loop rejects: a driver status other than kOk (the sample is skipped, the
// estimator drops its anchor), a fault cause already raised in the cycle, the model's own
// rejection, or an estimate outside the physical range (the anchor is dropped after it). A
// hot swap is refused (kInvalid, handed back): the learned drift is relative to the running
// model. kAdapt freezes and resumes learning.
//
// Health (LoopConfig::health_enabled): the loop steps adaptation::HealthEstimator with the
// measured E and D of every cycle (a sample with any fault cause in its cycle is passed as
// rejected) and, under adaptation, the model's predicted D for the same field path (the loop
// the loss of polarisation is measured against; without adaptation none) and evaluates the alarm
// bands (adaptation::HealthAlarms) every status period, with the adaptation's equivalent
// temperature when it runs. An alarm latches as a warning (status `health`); with bands.fault it is
// also Fault::kHealth, a cause in every cycle while it is beyond its band. Its state (the
// estimator's, then the alarms' latches) is saved with the model's by kSaveState and restored by
// restore_health_state() before the first cycle, so a restart keeps the baseline, the trends and
// the latched warnings. kReset clears the warnings back inside their bands, in any state; a reset
// it answers with a refusal changes nothing (not the supervisor, not a warning):
//   faulted, a fault cause in the last cycle      kRefusedCause
//   faulted, no cause                             kDone: faults and clearable warnings cleared
//   not faulted, a warning back inside its band   kDone: those warnings cleared
//   not faulted, warnings all beyond their bands  kRefusedCause
//   not faulted, no warning latched               kRefusedState (nothing to reset)
//
// Threads: cycle() runs on the real-time thread only. submit(), take_answer(), take_retired()
// and status() are for one control thread (single producer / single consumer rings), status()
// for any thread. cycle() is real-time safe: no allocation, lock, exception, blocking call or
// I/O besides the driver's non-blocking read and write (tests/runtime/loop_realtime_test.cpp).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>

#include "selfsense/adaptation/adapted_reconstruction.hpp"
#include "selfsense/adaptation/health_alarms.hpp"
#include "selfsense/adaptation/health_estimator.hpp"
#include "selfsense/control/wave_generator.hpp"
#include "selfsense/models/runtime_model.hpp"
#include "selfsense/runtime/controller.hpp"
#include "selfsense/runtime/driver.hpp"
#include "selfsense/runtime/latest_value.hpp"
#include "selfsense/runtime/loop_command.hpp"
#include "selfsense/runtime/loop_sample.hpp"
#include "selfsense/runtime/spsc_ring.hpp"
#include "selfsense/runtime/status_snapshot.hpp"
#include "selfsense/runtime/supervisor.hpp"

namespace selfsense::runtime {

enum class SafeOutput : std::uint8_t { kZero, kHold };

struct LoopConfig {
  double sample_time{1e-4};  // [s]
  SafeOutput safe_output{SafeOutput::kZero};
  double safe_value{0.0};    // E [V/m] written by kZero ("zero" field, or a configured bias)
  double strain_min{-2e-3};  // physical range of S_hat [-]; outside: kEstimateOutOfRange
  double strain_max{3e-3};
  double stress_min{-1e8};  // [Pa]
  double stress_max{1e8};
  OverrunPolicy overrun{};
  // Armed on socket setpoints: fault if none within it; 0: off. A wave feeds it while it plays;
  // when the wave ends or is stopped the held setpoint has watchdog_s from then.
  double watchdog_s{0.0};
  std::uint32_t status_period{100};  // cycles between status snapshots
  std::size_t command_capacity{64};
  // With the adapted reconstruction: the driver's temp_ref, where finite, replaces the
  // estimate in that cycle (AdaptedReconstruction::set_temperature; clear_temperature() in a
  // cycle without it).
  bool adaptation_temperature{false};
  // With the adapted reconstruction the feedforward's inverse takes the adapted actuator
  // (AdaptedReconstruction::feedforward_scales()) in every cycle with a measured temperature and
  // a model with fitted coefficients; with this also from the drift estimated from E and D (the
  // frozen drift while frozen). Otherwise, and without adaptation, the actuator as identified
  // (scales 1). Off by default: on the daemon's bench the estimate's scales made the open loop's
  // tracking worse (docs/adaptation.md, "The feedforward with the adapted parameters").
  bool adaptation_feedforward_estimate{false};
  bool health_enabled{false};
  adaptation::HealthEstimatorConfig health{};
  adaptation::HealthBands health_bands{};

  [[nodiscard]] bool is_valid(std::string* why) const;
};

// Where recorded samples go (the recorder's ring). Real-time safe: never blocks.
class SampleSink {
 public:
  SampleSink() = default;
  SampleSink(const SampleSink&) = delete;
  SampleSink& operator=(const SampleSink&) = delete;
  SampleSink(SampleSink&&) = delete;
  SampleSink& operator=(SampleSink&&) = delete;
  virtual ~SampleSink() = default;
  // False when the sample could not be taken (counted by the loop as dropped).
  virtual bool push(const LoopSample& sample) noexcept = 0;
};

class Loop final {  // NOLINT(clang-analyzer-optin.performance.Padding): members in reading order
 public:
  // Throws std::invalid_argument on an invalid configuration. The driver must be active before
  // the first cycle; the sink may be null (nothing recorded).
  Loop(const LoopConfig& config, Driver& driver, std::unique_ptr<models::Reconstruction> model,
       const Controller& controller, SampleSink* sink);
  // The adapted reconstruction instead of the plain one (header comment).
  Loop(const LoopConfig& config, Driver& driver,
       std::unique_ptr<adaptation::AdaptedReconstruction> model, const Controller& controller,
       SampleSink* sink);
  Loop(const Loop&) = delete;
  Loop& operator=(const Loop&) = delete;
  Loop(Loop&&) = delete;
  Loop& operator=(Loop&&) = delete;
  ~Loop();

  // One cycle. overrun: the pacer found this cycle's deadline already past; missed: the
  // deadlines that passed without a cycle before it (a stall), which the overrun policy counts
  // as overruns in a row.
  void cycle(bool overrun, std::int64_t missed = 0) noexcept;

  // Control thread.
  bool submit(const LoopCommand& command) noexcept { return commands_.try_push(command); }
  bool take_answer(LoopAnswer& out) noexcept { return answers_.try_pop(out); }
  bool take_retired(Retired& out) noexcept { return retired_.try_pop(out); }
  // Any thread: the newest published snapshot.
  [[nodiscard]] StatusSnapshot status() const noexcept { return published_.read(); }
  // The loop thread's own view (tests, the runner that adds timing).
  [[nodiscard]] const StatusSnapshot& local_status() const noexcept { return status_; }
  // Timing figures from the runner, published with the next snapshot.
  void set_timing(const StatusSnapshot& timing) noexcept;

  // The health state: adaptation::HealthEstimator's, then adaptation::HealthAlarms' (latched
  // bits and raise times). 0 when health is off.
  static constexpr std::size_t kHealthStateSize{adaptation::HealthEstimator::kStateSize +
                                                adaptation::HealthAlarms::kStateSize};
  [[nodiscard]] std::size_t health_state_size() const noexcept {
    return health_ ? kHealthStateSize : 0;
  }
  // Before the first cycle (the loop thread not yet running): false, nothing restored, when
  // health is off or the span's size is not health_state_size(). The status shows it at once.
  bool restore_health_state(std::span<const double> in) noexcept;

  [[nodiscard]] const Supervisor& supervisor() const noexcept { return supervisor_; }
  [[nodiscard]] const Controller& controller() const noexcept { return controller_; }
  [[nodiscard]] const LoopConfig& config() const noexcept { return config_; }

 private:
  Loop(const LoopConfig& config, Driver& driver, std::unique_ptr<models::Reconstruction> model,
       std::unique_ptr<adaptation::AdaptedReconstruction> adapted, const Controller& controller,
       SampleSink* sink);
  void handle(const LoopCommand& c) noexcept;
  void answer(const LoopCommand& c, CommandResult r) noexcept;
  [[nodiscard]] CommandResult reset() noexcept;
  [[nodiscard]] double safe_command() const noexcept;
  [[nodiscard]] double setpoint() noexcept;
  [[nodiscard]] models::Reconstruction::Estimate estimate(double e, double d) noexcept;
  void publish_adaptation() noexcept;
  void follow_health(bool accepted, double e, double d) noexcept;
  void publish_health() noexcept;

  LoopConfig config_;
  Driver* driver_;
  std::unique_ptr<models::Reconstruction> model_;
  std::unique_ptr<adaptation::AdaptedReconstruction> adapted_;  // null: no adaptation
  std::optional<adaptation::HealthEstimator> health_{};         // empty: no health
  std::optional<adaptation::HealthAlarms> alarms_{};
  Controller controller_;
  SampleSink* sink_;
  Supervisor supervisor_;
  SpscRing<LoopCommand> commands_;
  SpscRing<LoopAnswer> answers_;
  SpscRing<Retired> retired_;
  LatestValue<StatusSnapshot> published_{};
  StatusSnapshot status_{};

  std::unique_ptr<control::WaveGenerator> wave_{};
  bool wave_running_{false};
  double last_wave_value_{0.0};
  double hold_setpoint_{0.0};
  double command_{0.0};  // last written command E [V/m]
  std::int64_t cycle_{0};
  std::int64_t last_feed_{0};  // cycle of the last setpoint or heartbeat
  double s_hat_{0.0};
  double t_hat_{0.0};
  bool estimate_valid_{false};
  double predicted_d_{0.0};         // the adapted model's predicted D (health's reference), or NaN
  std::uint32_t active_causes_{0};  // faults seen in the current cycle
  // Ramped stop: the command it starts from, its length and the cycles left [cycles].
  double ramp_from_{0.0};
  std::int64_t ramp_cycles_{0};
  std::int64_t ramp_left_{0};
};

}  // namespace selfsense::runtime
