// Requests from the control thread to the real-time loop, and the loop's answers. Plain values
// carried through lock-free rings (spsc_ring.hpp). Objects that take allocation to build (a
// wave generator with its table, a re-identified model) are built on the control thread and
// handed over by pointer; the loop gives the ones it replaced back through the `retired` ring so
// they are freed off the real-time thread.
#pragma once

#include <cstdint>
#include <span>

#include "selfsense/runtime/controller.hpp"
#include "selfsense/runtime/loop_sample.hpp"

namespace selfsense::control {
class WaveGenerator;
}
namespace selfsense::models {
class Reconstruction;
struct SavedState;
}  // namespace selfsense::models

namespace selfsense::runtime {

enum class CommandKind : std::uint8_t {
  kArm,
  kDisarm,
  kReset,
  kSetpoint,   // value: the mode's quantity; stops a running wave
  kHeartbeat,  // feeds the setpoint watchdog without changing anything
  kMode,       // mode
  kWave,       // wave (ownership passes to the loop)
  kStopWave,   // hold the wave's last value
  kTune,       // tuning: gains, filters and command limits, all or nothing (a reload)
  kSwapModel,  // model and, when not null, feedforward (ownership passes to the loop; the
               // model takes the running one's memory); refused while armed
  kSaveState,  // state: the model's state is saved into it (sized by make_saved_state() for the
               // running model); kInvalid when it does not fit. health_state, when not empty:
               // the health estimate's and alarms' state too (Loop::health_state_size() values;
               // kInvalid when the size differs)
  kAdapt,      // value: 1 freezes the drift estimate (adaptation/drift_estimator.hpp), 0
               // resumes learning; kInvalid when the loop runs no adaptation
  kRampDown,   // value: seconds; while armed, the command ramps linearly from its last value
               // to the safe output over that time, then the loop disarms (a stop that does not
               // knock the stack; faults still go to the safe output at once); refused unless
               // armed
};

struct LoopCommand {
  std::uint64_t id{0};
  CommandKind kind{CommandKind::kHeartbeat};
  double value{0.0};
  ControlMode mode{ControlMode::kPosition};
  control::WaveGenerator* wave{nullptr};
  models::Reconstruction* model{nullptr};
  Tuning tuning{};
  Feedforward* feedforward{nullptr};   // kSwapModel: the controller's new inverse model
  models::SavedState* state{nullptr};  // kSaveState: owned by the sender, who waits for the answer
  std::span<double> health_state{};    // kSaveState: likewise
};

enum class CommandResult : std::uint8_t {
  kDone,
  kRefusedState,  // not allowed in the current state (arm while faulted, mode while armed...)
  kRefusedCause,  // reset while a fault cause is still active
  kInvalid,       // rejected by the control law (gains, filters, limits)
};

struct LoopAnswer {
  std::uint64_t id{0};
  CommandResult result{CommandResult::kDone};
  LoopState state{LoopState::kFaulted};
};

// Something the loop no longer uses, to be freed off the real-time thread.
struct Retired {
  control::WaveGenerator* wave{nullptr};
  models::Reconstruction* model{nullptr};
  Feedforward* feedforward{nullptr};  // holds the inverse model it replaced
};

}  // namespace selfsense::runtime
