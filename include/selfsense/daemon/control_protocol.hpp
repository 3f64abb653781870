// The control socket's protocol (docs/control-socket.md): line-delimited JSON, one request
// object per line, one reply object per line.
//
// A request names its kind in "request" and carries that kind's members only:
//   {"request": "status"}   "arm"   "disarm"   "reset"   "reload"
//   {"request": "setpoint", "value": 5e-4}            in the active mode's unit: S [-] in
//                                                     position (and open-loop), T [Pa] in force
//   {"request": "mode", "name": "force"}              position | force | open-loop | damping
//   {"request": "wave", "shape": "sine", "amplitude": 4e-4, "offset": 6e-4, "frequency_hz": 1,
//    "phase": 0, "repeat": 0}                         sine | triangle | square
//   {"request": "wave", "shape": "staircase", "levels": [0, 2e-4, 4e-4], "dwell_s": 0.5, ...}
//   {"request": "wave", "shape": "table", "values": [0, 1e-4, 3e-4], "dt_s": 0.01, ...}
//   {"request": "wave", "shape": "stop"}
//   {"request": "record", "action": "start"}          start | stop
//   {"request": "state", "action": "save"}            a dump of the model's memory
//   {"request": "adapt", "action": "freeze"}          freeze | resume | show: the online
//                                                     drift estimate (docs/adaptation.md)
//   {"request": "impulse", "force_n": 300, "duration_s": 5e-4}
//                                                     a force pulse on the stack from the
//                                                     bench (drivers with a force input: the
//                                                     simulated transducer), for a ring-down
// Parsing validates against RequestLimits, which the daemon fills from its configuration and
// its active mode: a setpoint, and every value a wave can reach, must lie inside the active
// mode's setpoint range. A rejected request gives one error that names the member
// ("setpoint.value: 0.02 is outside [-0.0001, 0.0015] for position"); unknown requests,
// unknown or duplicated members, wrong types, numbers beyond double range and nesting are
// errors. Parsing has no side effects, so a rejected request changes nothing.
//
// A reply always has "ok"; when false also "error" (a one-line message):
//   {"ok": true, ...}   {"ok": false, "error": "mode.name: \"fast\" is not a mode (...)"}
//
// Pure functions of their arguments; not for the real-time thread (they allocate and throw).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <variant>

#include "selfsense/control/wave_generator.hpp"
#include "selfsense/runtime/loop_sample.hpp"

namespace selfsense::daemon {

struct StatusRequest {
  bool operator==(const StatusRequest&) const = default;
};
struct ArmRequest {
  bool operator==(const ArmRequest&) const = default;
};
struct DisarmRequest {
  bool operator==(const DisarmRequest&) const = default;
};
struct ResetRequest {
  bool operator==(const ResetRequest&) const = default;
};
struct ReloadRequest {
  bool operator==(const ReloadRequest&) const = default;
};
struct SetpointRequest {
  double value{0.0};  // in the active mode's unit (RequestLimits::mode)
  bool operator==(const SetpointRequest&) const = default;
};
struct ModeRequest {
  runtime::ControlMode mode{runtime::ControlMode::kPosition};
  bool operator==(const ModeRequest&) const = default;
};
// A waveform for the setpoint, ready for control::WaveGenerator (its Config is valid at the
// limits' sample time), or stop: back to holding the last setpoint.
struct WaveRequest {
  bool stop{false};
  control::WaveGenerator::Config wave{};  // unused when stop
  bool operator==(const WaveRequest& other) const;
};
struct RecordRequest {
  enum class Action : std::uint8_t { kStart, kStop };
  Action action{Action::kStart};
  bool operator==(const RecordRequest&) const = default;
};

// A dump of the model's memory into the recorder's directory (daemon.hpp, dump_model_state).
struct StateRequest {
  enum class Action : std::uint8_t { kSave };
  Action action{Action::kSave};
  bool operator==(const StateRequest&) const = default;
};

// The online adaptation: freeze or resume learning (through the loop's command ring), or show
// the estimate.
struct AdaptRequest {
  enum class Action : std::uint8_t { kFreeze, kResume, kShow };
  Action action{Action::kShow};
  bool operator==(const AdaptRequest&) const = default;
};

// A rectangular force pulse on the stack through the driver's runtime::ForceInput.
struct ImpulseRequest {
  double force_n{0.0};     // [N], |force_n| <= RequestLimits::max_impulse_n
  double duration_s{0.0};  // [s], in [sample_time, max_impulse_s]
  bool operator==(const ImpulseRequest&) const = default;
};

using Request = std::variant<StatusRequest, ArmRequest, DisarmRequest, ResetRequest,
                             SetpointRequest, ModeRequest, WaveRequest, RecordRequest,
                             ReloadRequest, ImpulseRequest, StateRequest, AdaptRequest>;

struct SetpointRange {
  double min{0.0};
  double max{0.0};
};

// What a request may ask for; the daemon fills it from its configuration and active mode.
struct RequestLimits {
  static constexpr std::size_t kModes = 4;

  runtime::ControlMode mode{runtime::ControlMode::kPosition};  // the active mode
  // Setpoint range per mode (index: ControlMode); nullopt: the mode takes no setpoint or wave.
  std::array<std::optional<SetpointRange>, kModes> setpoint{};
  double sample_time{1e-4};            // [s] loop period: a wave must be playable at it
  double max_frequency_hz{1000.0};     // [Hz] > 0, a wave's frequency_hz
  std::size_t max_levels{1024};        // staircase levels
  std::size_t max_table_values{4096};  // table values (a line must also fit the socket's limit)
  double max_dwell_s{3600.0};          // [s] staircase dwell per level, table dt
  double max_impulse_n{1e4};           // [N] > 0, an impulse's force
  double max_impulse_s{1.0};           // [s] >= sample_time, an impulse's duration

  // False, with the violated constraint in *why, when the limits themselves are unusable.
  [[nodiscard]] bool is_valid(std::string* why) const;
};

// A parsed request, or the error that rejected it (request empty, error set).
struct ParsedRequest {
  std::optional<Request> request{};
  std::string error{};
};

// One line (without its newline) to a validated request. Never throws on any input bytes.
[[nodiscard]] ParsedRequest parse_request(std::string_view line, const RequestLimits& limits);
// The same for an already parsed JSON value.
[[nodiscard]] ParsedRequest parse_request_json(const nlohmann::json& value,
                                               const RequestLimits& limits);

// The request as the protocol writes it (what `selfsense ctl` sends); parse_request() of it
// gives it back when it is within the limits.
[[nodiscard]] nlohmann::json to_json(const Request& request);
// "status", "setpoint", ... : the value of the "request" member.
[[nodiscard]] std::string_view request_name(const Request& request);

// Protocol names of modes and back ("open-loop"); nullopt for an unknown name.
[[nodiscard]] std::string_view mode_name(runtime::ControlMode mode);
[[nodiscard]] std::optional<runtime::ControlMode> mode_from_name(std::string_view name);

// Replies. ok_reply(fields) adds "ok": true to an object of extra members (status figures).
[[nodiscard]] nlohmann::json ok_reply();
[[nodiscard]] nlohmann::json ok_reply(nlohmann::json fields);
[[nodiscard]] nlohmann::json error_reply(std::string_view error);
// One reply line with its newline; bytes that are not UTF-8 are replaced, so it never throws
// on the content of an error message.
[[nodiscard]] std::string reply_line(const nlohmann::json& reply);

}  // namespace selfsense::daemon
