// One cycle of the real-time loop as it leaves the loop: what the recorder writes, the flight
// recorder keeps and the telemetry summarises. A plain value (trivially copyable), handed over
// through lock-free rings (runtime/spsc_ring.hpp).
//
// Recording columns (docs/recorder.md, "File format"): t, E, D, T_hat, S_hat, setpoint, command,
// state, and S, T when the driver has references (the simulated transducer does); the rest are
// extensions any contract reader carries through.
#pragma once

#include <cstdint>
#include <limits>

namespace selfsense::runtime {

enum class LoopState : std::uint8_t { kFaulted = 0, kReady = 1, kArmed = 2 };

// "faulted", "ready", "armed": the names of the status JSON and the recordings' comments.
[[nodiscard]] constexpr const char* to_string(LoopState s) noexcept {
  switch (s) {
    case LoopState::kArmed:
      return "armed";
    case LoopState::kReady:
      return "ready";
    case LoopState::kFaulted:
      break;
  }
  return "faulted";
}

enum class ControlMode : std::uint8_t { kPosition = 0, kForce = 1, kOpenLoop = 2, kDamping = 3 };

struct LoopSample {
  static constexpr double kNone = std::numeric_limits<double>::quiet_NaN();

  std::int64_t cycle{0};           // loop cycle index since start
  double t{0.0};                   // [s] since the loop started (sample timestamp of the driver)
  double e{kNone};                 // E [V/m], measured
  double d{kNone};                 // D [C/m^2], measured
  double t_hat{kNone};             // T_hat [Pa], reconstructed
  double s_hat{kNone};             // S_hat [-], reconstructed
  double setpoint{kNone};          // in the mode's unit: S [-] (position), T [Pa] (force)
  double command{kNone};           // amplifier command as field E [V/m] after limits
  double s_ref{kNone};             // S [-] from a reference sensor, NaN without one
  double t_ref{kNone};             // T [Pa] from a reference sensor, NaN without one
  double temp_ref{kNone};          // the stack's temperature [degC] from the driver, or NaN
  double temp_equivalent{kNone};   // the adaptation's equivalent temperature [degC], or NaN
  std::uint32_t faults{0};         // bit set of runtime::Fault (latched)
  std::uint16_t driver_status{0};  // the driver's per-sample status word
  LoopState state{LoopState::kFaulted};
  ControlMode mode{ControlMode::kPosition};
  std::uint8_t estimate_status{0};  // models::SampleStatus
};

}  // namespace selfsense::runtime
