// The narrow seam between the loop and the hardware: one driver gives the loop its inputs (E
// and D, and reference S, T where a bench sensor exists) and takes the amplifier command.
// The simulated transducer (drivers/sim) is the first implementation; SPI, Modbus and CAN
// drivers stand behind the same interface.
//
// Lifecycle, each step once, in order, from the daemon's main thread (not real-time):
//   configure(setup)   check the setup against the device, allocate; an error names the cause
//   activate()         open the device, start its threads; the output is at its safe value
//   read() / write()   once per loop cycle, on the real-time thread
//   deactivate()       safe output, stop threads, close; also called after a failed activate
// read() and write() are real-time safe: noexcept, no allocation, no lock, no blocking I/O
// (bus drivers move blocking I/O to their own threads and hand samples over lock-free), and
// report through a status code, never an exception.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <string_view>

#include "selfsense/runtime/cycle_trigger.hpp"

namespace selfsense::runtime {

enum class DriverStatus : std::uint8_t {
  kOk = 0,
  kTimeout = 1,       // no sample in time
  kStale = 2,         // the sample repeats the last one (missed data-ready, stuck converter)
  kBadData = 3,       // CRC error, NaN or out-of-range raw value
  kDeviceFault = 4,   // the device reports a fault (amplifier fault line, converter error)
  kDisconnected = 5,  // no link to the device
  kNotActive = 6,     // called outside activate() .. deactivate()
};
[[nodiscard]] std::string_view to_string(DriverStatus s) noexcept;

struct InputSample {
  static constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
  double e{kNone};                 // E [V/m]
  double d{kNone};                 // D [C/m^2]
  double s_ref{kNone};             // S [-] from a reference sensor, NaN without one
  double t_ref{kNone};             // T [Pa] from a reference sensor, NaN without one
  double temp_ref{kNone};          // the stack's temperature [degC], NaN without a sensor
  std::int64_t timestamp_ns{0};    // sampling instant on the loop's clock
  std::uint16_t device_status{0};  // the device's own status bits, for the recording
};

struct OutputCommand {
  double e{0.0};  // commanded field E [V/m] (the driver scales to its DAC or register)
};

struct DriverSetup {
  double sample_time{0.0};  // [s] of the loop
};

// One counter a driver keeps beyond the common ones, under the driver's own name. The name is a
// string literal (static storage, never freed), so DriverCounters stays trivially copyable and
// crosses the loop's status seqlock as plain words, and filling it allocates nothing.
struct NamedCount {
  const char* name{nullptr};  // lower_snake_case, unique within the driver
  std::uint64_t value{0};
};

// Counters a driver keeps (read from any thread; the owning driver writes them). The common
// fields mean the same for every driver (docs/drivers/*.md say what each driver counts in
// them); `events` carries every other counter the driver keeps, so that all of them reach the
// daemon's status (`counters.driver_events`) and telemetry (selfsense_driver_events_total).
struct DriverCounters {
  static constexpr std::size_t kMaxEvents = 16;

  std::uint64_t reads{0};
  std::uint64_t writes{0};
  std::uint64_t errors{0};
  std::uint64_t timeouts{0};
  std::uint64_t stale{0};
  std::uint64_t bad_data{0};
  std::uint64_t retries{0};
  std::uint64_t reconnects{0};
  std::uint64_t device_faults{0};
  std::uint64_t crc_errors{0};  // frames whose checksum failed, either direction (0: no CRC)
  std::array<NamedCount, kMaxEvents> events{};
  std::size_t event_count{0};

  // Appends a driver-specific counter; false (and nothing stored) when all kMaxEvents slots are
  // taken. Real-time safe.
  bool add_event(const char* name, std::uint64_t value) noexcept {
    if (event_count >= kMaxEvents) return false;
    events[event_count++] = NamedCount{name, value};
    return true;
  }
  [[nodiscard]] std::span<const NamedCount> event_list() const noexcept {
    return {events.data(), event_count};
  }
};

// An external force a test bench can put on the stack on request (the simulated transducer's
// load; on a rig, a shaker or an impact hammer the driver commands): a rectangular pulse of
// `newtons` [N] for `seconds` [s] from the next cycle on, added to any constant load. For a
// damping run's ring-down. Called from the control thread while the loop runs: apply() is
// thread-safe and never blocks the loop.
class ForceInput {
 public:
  ForceInput() = default;
  ForceInput(const ForceInput&) = delete;
  ForceInput& operator=(const ForceInput&) = delete;
  ForceInput(ForceInput&&) = delete;
  ForceInput& operator=(ForceInput&&) = delete;
  virtual ~ForceInput() = default;
  // newtons finite, seconds > 0; a pulse replaces one still running.
  virtual void apply(double newtons, double seconds) noexcept = 0;
};

class Driver {
 public:
  Driver() = default;
  Driver(const Driver&) = delete;
  Driver& operator=(const Driver&) = delete;
  Driver(Driver&&) = delete;
  Driver& operator=(Driver&&) = delete;
  virtual ~Driver() = default;

  [[nodiscard]] virtual std::string_view name() const noexcept = 0;
  // False with *why naming the problem (a setting, the device's answer).
  virtual bool configure(const DriverSetup& setup, std::string* why) = 0;
  virtual bool activate(std::string* why) = 0;
  virtual DriverStatus read(InputSample& out) noexcept = 0;
  virtual DriverStatus write(const OutputCommand& command) noexcept = 0;
  virtual void deactivate() noexcept = 0;

  // Whether read() fills s_ref and t_ref.
  [[nodiscard]] virtual bool has_references() const noexcept { return false; }
  // Whether read() fills temp_ref (the recording's `temp` column).
  [[nodiscard]] virtual bool has_temperature() const noexcept { return false; }
  // Every counter the driver keeps, the common ones and its own (events). The loop calls it on
  // its real-time thread every status_period cycles for the status snapshot: real-time safe
  // (loads of atomics, nothing allocated, no lock), and the same event names in the same order
  // on every call.
  [[nodiscard]] virtual DriverCounters counters() const noexcept = 0;
  // When the device paces the loop (its data-ready edge starts each cycle), the trigger to wait
  // on instead of the timer; null otherwise (the default). Valid while the driver is active.
  [[nodiscard]] virtual CycleTrigger* cycle_trigger() noexcept { return nullptr; }
  // The bench's force input when the driver has one (the simulated transducer); null otherwise
  // (the default). Valid while the driver lives.
  [[nodiscard]] virtual ForceInput* force_input() noexcept { return nullptr; }
};

}  // namespace selfsense::runtime
