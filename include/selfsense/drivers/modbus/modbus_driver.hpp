// The Modbus driver of the loop (TCP or RTU over libmodbus) behind runtime::Driver
// (docs/drivers/modbus.md).
//
// Threads. Every blocking bus call runs on the driver's own bus thread, started by activate()
// and joined by deactivate(). The bus thread, once per poll period (absolute deadlines on
// CLOCK_MONOTONIC):
//   1. reads the input registers (one transaction per table, input and holding, spanning the
//      mapped inputs), decodes E, D (S_ref, T_ref, status) and publishes the sample;
//   2. waits up to half a period for the loop's command computed from that sample;
//   3. writes the newest command (when it has not been written yet) to the command register.
// Samples reach read() and commands leave write() through sequence-locked slots
// (runtime::LatestValue): neither side ever waits for the other.
//
// read() (real-time safe) answers with the newest sample and a status:
//   kNotActive     outside activate() .. deactivate()
//   kDisconnected  no link to the device (the bus thread reconnects with back-off)
//   kTimeout       the newest sample is older than sample_timeout_s, or none has arrived
//   kBadData       a value decoded to NaN/infinity or outside its register's range
//   kStale         the held sample is older than max_age_s (by its timestamp, the end of the
//                  poll that read it; younger samples are answered kOk even when read again, a
//                  zero-order hold across bus jitter; each kStale counts in counters().stale).
//                  Age, not a count of reads: a loop that wakes late and runs a burst of cycles
//                  does not use up an allowance.
//   kOk            otherwise
// write() (real-time safe) hands the command over; kDisconnected while there is no link.
//
// Counters (bus thread; any thread may read them):
//   errors         failed transactions, whatever the cause
//   timeouts       transactions not answered within the response/byte timeout
//   retries        polls that follow a failed poll on the same connection
//   reconnects     links re-established after a loss
//   bad_data       answers with a CRC or framing error, wrong length, transaction or unit, and
//                  values decoding to NaN or out of range
//   device_faults  exception responses (the device refused: illegal address, function, ...)
//   crc_errors     RTU answers whose CRC failed (also in bad_data; TCP has no CRC)
// Events (DriverCounters::events): exception_responses, polls, late_commands,
// missed_deadlines (BusStats' counts).
#pragma once

#include <atomic>
#include <cstdint>
#include <string>
#include <thread>
#include <vector>

#include "selfsense/drivers/modbus/modbus_config.hpp"
#include "selfsense/runtime/driver.hpp"
#include "selfsense/runtime/latency_histogram.hpp"
#include "selfsense/runtime/latest_value.hpp"

struct _modbus;  // NOLINT(bugprone-reserved-identifier): libmodbus's context (modbus_t)

namespace selfsense::drivers::modbus {

// Figures of the bus thread (bench and tests), read from any thread.
struct BusStats {
  std::uint64_t polls{0};        // input reads that published a sample
  std::uint64_t poll_ns_sum{0};  // time spent in the input read transactions
  std::uint64_t poll_ns_max{0};
  std::uint64_t latencies{0};       // commands written in the poll of the sample they follow
  std::uint64_t latency_ns_sum{0};  // sample published -> its command written on the bus
  std::uint64_t latency_ns_max{0};
  std::uint64_t late_commands{0};     // commands written in a later poll than their sample's
  std::uint64_t missed_deadlines{0};  // polls started more than a period late (skipped ahead)
};

// What crosses between the loop and the bus thread.
struct BusSample {
  runtime::InputSample in{};
  std::uint64_t seq{0};  // 0: none yet
  std::int64_t received_ns{0};
  bool bad{false};
};
struct BusCommand {
  double e{0.0};
  std::uint64_t seq{0};         // 0: none yet
  std::uint64_t sample_seq{0};  // the newest sample read() had seen
};

class ModbusDriver final : public runtime::Driver {
 public:
  explicit ModbusDriver(ModbusConfig config);
  ~ModbusDriver() override;
  ModbusDriver(const ModbusDriver&) = delete;
  ModbusDriver& operator=(const ModbusDriver&) = delete;
  ModbusDriver(ModbusDriver&&) = delete;
  ModbusDriver& operator=(ModbusDriver&&) = delete;

  [[nodiscard]] std::string_view name() const noexcept override {
    return config_.transport == Transport::kTcp ? "modbus-tcp" : "modbus-rtu";
  }
  bool configure(const runtime::DriverSetup& setup, std::string* why) override;
  bool activate(std::string* why) override;
  runtime::DriverStatus read(runtime::InputSample& out) noexcept override;
  runtime::DriverStatus write(const runtime::OutputCommand& command) noexcept override;
  void deactivate() noexcept override;
  [[nodiscard]] bool has_references() const noexcept override {
    return config_.registers.s_ref.enabled || config_.registers.t_ref.enabled;
  }
  // With `registers.temp`: read() fills temp_ref [degC] (the recording's `temp` column).
  [[nodiscard]] bool has_temperature() const noexcept override {
    return config_.registers.temp.enabled;
  }
  [[nodiscard]] runtime::DriverCounters counters() const noexcept override;

  [[nodiscard]] bool connected() const noexcept {
    return connected_.load(std::memory_order_acquire);
  }
  [[nodiscard]] std::uint64_t exception_responses() const noexcept {
    return device_faults_.load(std::memory_order_relaxed);
  }
  [[nodiscard]] BusStats bus_stats() const noexcept;
  // Distributions of the same figures; owned by the bus thread: read them after deactivate().
  [[nodiscard]] const runtime::LatencyHistogram& latency_histogram() const noexcept {
    return latency_hist_;
  }
  [[nodiscard]] const runtime::LatencyHistogram& poll_histogram() const noexcept {
    return poll_hist_;
  }
  // False when `priority` was asked for and the system refused it (the thread runs anyway).
  [[nodiscard]] bool bus_priority_granted() const noexcept { return priority_granted_; }
  [[nodiscard]] const ModbusConfig& config() const noexcept { return config_; }

 private:
  using Sample = BusSample;
  using Command = BusCommand;
  struct Block {  // one read transaction
    bool used{false};
    int first{0};
    int count{0};
  };

  void run_bus() noexcept;
  bool connect_bus() noexcept;
  void disconnect_bus() noexcept;
  bool poll_inputs(std::uint64_t seq) noexcept;
  bool write_command(const Command& c) noexcept;
  // Counts a failed transaction by errno; false when the link must be re-opened.
  bool count_failure(int err) noexcept;
  void sleep_for_ns(std::int64_t ns) const noexcept;

  ModbusConfig config_;
  std::int64_t period_ns_{0};
  std::int64_t sample_timeout_ns_{0};
  std::int64_t max_age_ns_{0};
  _modbus* ctx_{nullptr};
  std::thread bus_{};
  std::atomic<bool> stop_{false};
  std::atomic<bool> connected_{false};
  bool active_{false};
  bool priority_granted_{true};

  runtime::LatestValue<Sample> samples_{};    // bus -> loop
  runtime::LatestValue<Command> commands_{};  // loop -> bus

  // Loop thread only.
  Sample held_{};
  std::uint64_t command_seq_{0};

  // Bus thread only.
  std::array<Block, 2> blocks_{};  // [input, holding]
  std::array<std::uint16_t, std::size_t{2} * 125> words_{};
  std::uint64_t written_seq_{0};
  std::uint64_t published_seq_{0};
  std::int64_t published_ns_{0};
  int failures_in_row_{0};
  runtime::LatencyHistogram latency_hist_{};
  runtime::LatencyHistogram poll_hist_{};
  bool ever_connected_{false};

  std::atomic<std::uint64_t> reads_{0};
  std::atomic<std::uint64_t> writes_{0};
  std::atomic<std::uint64_t> stale_{0};
  std::atomic<std::uint64_t> errors_{0};
  std::atomic<std::uint64_t> timeouts_{0};
  std::atomic<std::uint64_t> retries_{0};
  std::atomic<std::uint64_t> reconnects_{0};
  std::atomic<std::uint64_t> bad_data_{0};
  std::atomic<std::uint64_t> device_faults_{0};
  std::atomic<std::uint64_t> crc_errors_{0};
  std::atomic<std::uint64_t> polls_{0};
  std::atomic<std::uint64_t> poll_ns_sum_{0};
  std::atomic<std::uint64_t> poll_ns_max_{0};
  std::atomic<std::uint64_t> latencies_{0};
  std::atomic<std::uint64_t> latency_ns_sum_{0};
  std::atomic<std::uint64_t> latency_ns_max_{0};
  std::atomic<std::uint64_t> late_commands_{0};
  std::atomic<std::uint64_t> missed_deadlines_{0};
};

}  // namespace selfsense::drivers::modbus
