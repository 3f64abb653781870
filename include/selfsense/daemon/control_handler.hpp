// The daemon's answers to control-socket requests (docs/control-socket.md): validated
// requests (control_protocol.hpp) become loop commands, recorder actions or a status reply.
// Runs on the control server's thread; never on the real-time thread.
//
//   status          state, mode, faults (latched names), counters, timing, recording, estimate
//   arm             refused while faulted, without an estimate yet, or without real-time set-up
//                   (unless degraded timing is allowed); bumpless at the measured state
//   disarm, reset   reset is refused while a fault's cause is still present
//   setpoint VALUE  in the active mode's unit, inside the configured setpoint range
//   mode NAME       bumpless, also while armed
//   wave ...        built here (allocation) and handed to the loop by pointer
//   record start|stop, reload
#pragma once

#include <nlohmann/json.hpp>

#include "selfsense/daemon/control_server.hpp"
#include "selfsense/runtime/loop_command.hpp"

namespace selfsense::daemon {

class Daemon;

class ControlHandler final : public RequestHandler {
 public:
  explicit ControlHandler(Daemon& daemon) : daemon_(&daemon) {}
  [[nodiscard]] RequestLimits limits() override;
  nlohmann::json handle(const Request& request, const PeerCredentials& peer) override;

 private:
  nlohmann::json status();
  nlohmann::json send(runtime::LoopCommand command, const char* what, bool* submitted = nullptr);

  Daemon* daemon_;
};

}  // namespace selfsense::daemon
