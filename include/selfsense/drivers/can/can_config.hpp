// The CAN driver's section of the daemon's configuration: the interface, timing limits and the
// signal definitions (as a DBC file gives them) of the inputs E, D (optional S_ref, T_ref and the
// stack's temperature) and of the command. Read strictly from YAML; every problem names its key.
// Not real-time code.
//
//   driver:
//     type: can
//     interface: vcan0          # the SocketCAN network interface (<= 15 characters)
//     fd: false                 # true: CAN FD frames (CAN_RAW_FD_FRAMES; interface MTU 72)
//     rx_timeout_ms: 20         # E or D older than this: read() reports a timeout
//     stale_cycles: 0           # this many reads in a row without a new input frame: stale; 0 off
//     error_frames: true        # subscribe to error frames (counted; bus-off disconnects)
//     priority: 0               # the bus thread's SCHED_FIFO priority (1..99); 0: normal
//     temp_timeout_ms: 1000     # a temperature older than this reads as none (NaN), not a fault
//     signals:                  # e, d, command required; s_ref and t_ref together or not at all;
//                               # temp [degC] optional (the recording's `temp` column)
//       e: {id: 0x101, extended: false, start_bit: 0, length: 32, byte_order: little,
//           signed: true, scale: 1.0, offset: 0.0}
//       ...                     # `byte: N` instead of start_bit: the signal starts at byte N
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "selfsense/drivers/can/can_codec.hpp"
#include "selfsense/io/yaml_map.hpp"

namespace selfsense::drivers::can {

struct SignalConfig {
  FrameId frame{};
  Signal signal{};
  bool present{false};
};

// One frame of the layout and the data bytes its signals need.
struct FrameLayout {
  FrameId id{};
  std::size_t bytes{0};
};

struct CanConfig {
  std::string interface {};
  bool fd{false};
  double rx_timeout_ms{20.0};
  std::uint32_t stale_cycles{0};
  bool error_frames{true};
  int priority{0};  // bus thread SCHED_FIFO priority; 0: normal scheduling
  double temp_timeout_ms{1000.0};
  SignalConfig e{};
  SignalConfig d{};
  SignalConfig s_ref{};
  SignalConfig t_ref{};
  SignalConfig temp{};  // the stack's temperature [degC]
  SignalConfig command{};

  [[nodiscard]] std::size_t max_bytes() const noexcept {
    return fd ? kFdMaxBytes : kClassicMaxBytes;
  }
  [[nodiscard]] bool has_references() const noexcept { return s_ref.present && t_ref.present; }
  [[nodiscard]] bool has_temperature() const noexcept { return temp.present; }
  // The distinct frames that carry inputs, in the order e, d, s_ref, t_ref, temp first name them.
  [[nodiscard]] std::vector<FrameLayout> input_frames() const;
  // Data length of a frame carrying these bytes on this bus (an FD length when fd).
  [[nodiscard]] std::size_t frame_length(std::size_t bytes) const noexcept;
};

// Reads the driver section's own keys (driver.type is already read) into out; appends each
// value problem, located at its key ("FILE:LINE: driver.signals.e.length: ..."). Structural
// problems (unknown keys, wrong types) throw io::YamlError like every strict read.
void read_can_config(io::YamlMap& driver, double loop_rate_hz, CanConfig& out,
                     std::vector<std::string>& problems);

}  // namespace selfsense::drivers::can
