// The SocketCAN driver of the loop (runtime::Driver): the inputs E, D (and S_ref, T_ref, the
// stack's temperature) arrive in CAN or CAN FD frames laid out as the configuration's signal
// definitions say (can_config.hpp, codec in can_codec.hpp); the command E leaves in a frame of its
// own. docs/drivers/can.md.
//
// Threads. activate() opens a raw CAN socket (bound to the interface, filtered to the input
// frames and, when enabled, error frames) and starts the bus thread: it blocks in poll() with a
// timeout, decodes every frame, keeps the newest value of each signal and publishes the whole
// input set, with the receive time of E and D, through a LatestValue (a sequence lock: the bus
// thread never waits for the loop). read() on the real-time thread takes the newest set without
// waiting (a bounded number of attempts; if a publish overlapped them all, the set read last
// time is used again). write() encodes nothing and sends nothing: it publishes the command
// through a second LatestValue and wakes the bus thread with one non-blocking eventfd write (a
// counter increment in the kernel: no bus I/O, never waits), and the bus thread encodes the
// command and sends it. The loop thread thus does no bus I/O; the hand-over costs the bus
// thread's wake-up (tx_latency(): from write() to the send). With `priority` set the bus
// thread runs under SCHED_FIFO (as the Modbus driver's does).
//
// Statuses of read(): kTimeout when E or D is older than rx_timeout_ms (or never arrived),
// kDisconnected while the controller is bus-off (from a CAN_ERR_BUSOFF error frame until
// CAN_ERR_RESTARTED, or until an input frame arrives after read() has reported the bus-off), kStale
// after stale_cycles reads in a row without a new input frame (0: off), kOk otherwise. A
// temperature older than temp_timeout_ms (or none yet) is read as NaN and counted
// (temp_timeouts), not a fault: it is slow and the loop runs without it (the adaptation learns
// from E and D alone in such cycles).
//
// Counters (DriverCounters): reads, writes (command frames sent by the bus thread), errors
// (error frames received and failed sends), timeouts, stale (reads that returned those),
// bad_data (input frames shorter than their signals need, dropped), retries (commands not sent
// on a full TX queue), reconnects (recoveries from bus-off), device_faults (bus-off events),
// crc_errors (error frames reporting a protocol violation in the CRC sequence or delimiter).
// Events (DriverCounters::events): rx_frames, error_frames, tx_errors, tx_queue_full,
// rx_timeouts, bus_off_reads, bus_off, command_saturated, commands_superseded, temp_timeouts.
#pragma once

#include <linux/can.h>

#include <atomic>
#include <cstdint>
#include <string>
#include <thread>

#include "selfsense/drivers/can/can_config.hpp"
#include "selfsense/runtime/driver.hpp"
#include "selfsense/runtime/latency_histogram.hpp"
#include "selfsense/runtime/latest_value.hpp"

namespace selfsense::drivers::can {

// Bits of InputSample::device_status.
inline constexpr std::uint16_t kStatusBusOff = 1U << 0U;
inline constexpr std::uint16_t kStatusErrorPassive = 1U << 1U;

// Beyond DriverCounters, for the documentation's figures and the tests.
struct CanCounters {
  std::uint64_t rx_frames{0};            // frames received (data and error)
  std::uint64_t error_frames{0};         // of which error frames
  std::uint64_t tx_frames{0};            // command frames sent
  std::uint64_t command_saturated{0};    // commands outside the signal's raw range (clamped)
  std::uint64_t commands_superseded{0};  // handed over but replaced before the bus thread sent them
};

// A command handed from write() to the bus thread.
struct CanCommand {
  double e{0.0};
  std::uint64_t seq{0};       // 0: none yet
  std::int64_t inputs_ns{0};  // arrival of the newest input frame it was computed from (0: its
                              // cycle's read() was not kOk)
  std::int64_t handed_ns{0};  // when write() handed it over
};

// The input set the bus thread publishes to read().
struct CanInputs {
  runtime::InputSample sample{};
  std::uint64_t sequence{0};  // input frames accepted so far
  std::int64_t e_ns{0};       // arrival of the newest E (0: none yet)
  std::int64_t d_ns{0};
  std::int64_t temp_ns{0};    // arrival of the newest temperature (0: none yet)
  std::int64_t newest_ns{0};  // arrival of the newest input frame
};

class CanDriver final : public runtime::Driver {
 public:
  explicit CanDriver(CanConfig config);
  ~CanDriver() override;
  CanDriver(const CanDriver&) = delete;
  CanDriver& operator=(const CanDriver&) = delete;
  CanDriver(CanDriver&&) = delete;
  CanDriver& operator=(CanDriver&&) = delete;

  [[nodiscard]] std::string_view name() const noexcept override { return "can"; }
  bool configure(const runtime::DriverSetup& setup, std::string* why) override;
  bool activate(std::string* why) override;
  runtime::DriverStatus read(runtime::InputSample& out) noexcept override;
  runtime::DriverStatus write(const runtime::OutputCommand& command) noexcept override;
  void deactivate() noexcept override;
  [[nodiscard]] bool has_references() const noexcept override { return config_.has_references(); }
  [[nodiscard]] bool has_temperature() const noexcept override { return config_.has_temperature(); }
  [[nodiscard]] runtime::DriverCounters counters() const noexcept override;
  [[nodiscard]] CanCounters can_counters() const noexcept;

  // Latencies (read them after deactivate()). Recorded by the bus thread: from the arrival of
  // the newest input frame to the send of the command computed from it (cycles whose read()
  // returned kOk), and from write()'s hand-over to the send. Recorded by write() on the
  // real-time thread: from read() to write().
  [[nodiscard]] const runtime::LatencyHistogram& rx_to_tx() const noexcept { return rx_to_tx_; }
  [[nodiscard]] const runtime::LatencyHistogram& read_to_write() const noexcept {
    return read_to_write_;
  }
  [[nodiscard]] const runtime::LatencyHistogram& tx_latency() const noexcept { return tx_latency_; }
  // False when `priority` was asked for and the system refused it (the thread runs anyway).
  [[nodiscard]] bool bus_priority_granted() const noexcept { return priority_granted_; }

 private:
  // One input signal and where it goes.
  struct Slot {
    SignalConfig config{};
    std::size_t bytes{0};
    double runtime::InputSample::*field{nullptr};
  };

  void bus_loop() noexcept;
  void on_frame(const canfd_frame& frame, std::int64_t now_ns) noexcept;
  // Bus thread: sends the newest handed-over command unless it was sent already.
  void send_command() noexcept;
  // Encodes e into tx_ and sends it; true when sent.
  bool send_frame(double e) noexcept;

  CanConfig config_;
  std::array<Slot, 5> slots_{};
  std::int64_t rx_timeout_ns_{0};
  std::int64_t temp_timeout_ns_{0};
  int socket_{-1};
  int wake_fd_{-1};  // eventfd: write() wakes the bus thread
  bool priority_granted_{true};
  bool configured_{false};
  bool active_{false};
  std::thread thread_{};
  std::atomic<bool> stop_{false};
  runtime::LatestValue<CanInputs> latest_{};
  runtime::LatestValue<CanCommand> command_{};

  // Bus thread only (and deactivate() once it has joined).
  CanInputs building_{};
  std::uint64_t sent_seq_{0};
  canfd_frame tx_{};
  std::size_t tx_size_{CAN_MTU};
  runtime::LatencyHistogram rx_to_tx_{};
  runtime::LatencyHistogram tx_latency_{};

  // Real-time thread only.
  CanInputs last_{};
  std::uint64_t last_sequence_{0};
  std::uint32_t repeats_{0};
  std::int64_t activated_ns_{0};
  std::int64_t read_ns_{0};
  bool read_ok_{false};  // the last read() returned kOk (its inputs make the command)
  std::uint64_t command_seq_{0};
  runtime::LatencyHistogram read_to_write_{};

  // Each written by one thread, read by any.
  struct Atomics {
    std::atomic<std::uint64_t> reads{0}, writes{0}, tx_errors{0}, timeouts{0}, stale{0},
        bad_data{0}, retries{0}, reconnects{0}, bus_off{0}, rx_frames{0}, error_frames{0},
        saturated{0}, disconnected{0}, superseded{0}, crc_errors{0}, temp_timeouts{0};
  };
  Atomics n_{};
  std::atomic<bool> bus_off_{false};
  std::atomic<bool> bus_off_seen_{false};  // a read() has returned kDisconnected for it
  std::atomic<bool> error_passive_{false};
  std::atomic<bool> send_failed_{false};  // the bus thread's last send failed (not a full queue)
};

}  // namespace selfsense::drivers::can
