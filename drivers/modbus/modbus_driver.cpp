#include "selfsense/drivers/modbus/modbus_driver.hpp"

#include <modbus.h>
#include <pthread.h>
#include <sched.h>
#include <sys/prctl.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <span>
#include <utility>

#include "selfsense/runtime/monotonic.hpp"

namespace selfsense::drivers::modbus {
namespace {

constexpr int kMaxReadRegisters = 125;  // one read transaction (Modbus application protocol)
constexpr std::int64_t kCommandPollNs = 10'000;

void update_max(std::atomic<std::uint64_t>& max, std::uint64_t value) noexcept {
  if (value > max.load(std::memory_order_relaxed)) max.store(value, std::memory_order_relaxed);
}

void bump(std::atomic<std::uint64_t>& counter) noexcept {
  counter.fetch_add(1, std::memory_order_relaxed);
}

std::pair<std::uint32_t, std::uint32_t> split_seconds(double s) noexcept {
  const auto us = static_cast<std::uint64_t>(std::llround(s * 1e6));
  return {static_cast<std::uint32_t>(us / 1'000'000), static_cast<std::uint32_t>(us % 1'000'000)};
}

}  // namespace

ModbusDriver::ModbusDriver(ModbusConfig config) : config_(std::move(config)) {}

ModbusDriver::~ModbusDriver() {
  deactivate();
}

bool ModbusDriver::configure(const runtime::DriverSetup& setup, std::string* why) {
  const auto fail = [why](std::string message) {
    if (why != nullptr) *why = std::move(message);
    return false;
  };
  const std::vector<std::string> problems = config_.problems();
  if (!problems.empty()) return fail("driver." + problems.front());
  if (!(setup.sample_time > 0.0)) return fail("modbus: the loop's sample time must be > 0");
  const double rate = config_.poll_rate_hz > 0.0 ? config_.poll_rate_hz : 1.0 / setup.sample_time;
  period_ns_ = std::llround(1e9 / rate);
  sample_timeout_ns_ = std::llround(config_.sample_timeout_s * 1e9);
  max_age_ns_ =
      config_.max_age_s > 0.0 ? std::llround(config_.max_age_s * 1e9) : period_ns_ * 5 / 2;
  blocks_ = {};
  for (const RegisterSpec* spec : config_.registers.inputs()) {
    if (!spec->enabled) continue;
    Block& b = blocks_[static_cast<std::size_t>(spec->function)];
    const int end = spec->address + word_count(spec->type);
    if (!b.used) {
      b = Block{true, spec->address, end - spec->address};
    } else {
      const int first = std::min(b.first, spec->address);
      b.count = std::max(b.first + b.count, end) - first;
      b.first = first;
    }
  }
  for (std::size_t i = 0; i < blocks_.size(); ++i) {
    if (blocks_[i].count > kMaxReadRegisters) {
      return fail("driver.registers: the " + std::string(to_string(static_cast<Function>(i))) +
                  " registers span " + std::to_string(blocks_[i].count) +
                  " addresses; one read transaction takes at most 125");
    }
  }
  return true;
}

bool ModbusDriver::activate(std::string* why) {
  if (period_ns_ == 0) {
    if (why != nullptr) *why = "modbus: activate() before configure()";
    return false;
  }
  if (active_) return true;
  if (config_.transport == Transport::kTcp) {
    ctx_ = modbus_new_tcp_pi(config_.host.c_str(), std::to_string(config_.port).c_str());
  } else {
    ctx_ = modbus_new_rtu(config_.device.c_str(), config_.baud, config_.parity, config_.data_bits,
                          config_.stop_bits);
  }
  if (ctx_ == nullptr) {
    if (why != nullptr) {
      *why = std::string("driver: libmodbus refused the settings: ") + modbus_strerror(errno);
    }
    return false;
  }
  modbus_set_slave(ctx_, config_.unit_id);
  const auto [rs, rus] = split_seconds(config_.response_timeout_s);
  modbus_set_response_timeout(ctx_, rs, rus);
  const auto [bs, bus] = split_seconds(config_.byte_timeout_s);
  modbus_set_byte_timeout(ctx_, bs, bus);
  held_ = Sample{};
  command_seq_ = 0;
  written_seq_ = 0;
  published_seq_ = 0;
  failures_in_row_ = 0;
  ever_connected_ = false;
  latency_hist_.reset();
  poll_hist_.reset();
  samples_.publish(Sample{});
  commands_.publish(Command{});
  stop_.store(false);
  connected_.store(false);
  bus_ = std::thread([this] { run_bus(); });
  priority_granted_ = true;
  if (config_.priority > 0) {
    sched_param param{};
    param.sched_priority = config_.priority;
    priority_granted_ = pthread_setschedparam(bus_.native_handle(), SCHED_FIFO, &param) == 0;
  }
  active_ = true;
  return true;
}

void ModbusDriver::deactivate() noexcept {
  if (bus_.joinable()) {
    // The safe output: a zero command, written by the bus thread before it stops.
    commands_.publish(Command{0.0, ++command_seq_, 0});
    stop_.store(true);
    bus_.join();
  }
  if (ctx_ != nullptr) {
    modbus_close(ctx_);
    modbus_free(ctx_);
    ctx_ = nullptr;
  }
  connected_.store(false);
  active_ = false;
}

runtime::DriverStatus ModbusDriver::read(runtime::InputSample& out) noexcept {
  if (!active_) return runtime::DriverStatus::kNotActive;
  bump(reads_);
  Sample s;
  if (samples_.try_read(s) && s.seq != held_.seq && s.seq != 0) held_ = s;
  out = held_.in;
  if (!connected_.load(std::memory_order_acquire)) return runtime::DriverStatus::kDisconnected;
  const std::int64_t age = runtime::monotonic_ns() - held_.received_ns;
  if (held_.seq == 0 || age > sample_timeout_ns_) return runtime::DriverStatus::kTimeout;
  if (held_.bad) return runtime::DriverStatus::kBadData;
  if (age > max_age_ns_) {
    bump(stale_);
    return runtime::DriverStatus::kStale;
  }
  return runtime::DriverStatus::kOk;
}

runtime::DriverStatus ModbusDriver::write(const runtime::OutputCommand& command) noexcept {
  if (!active_) return runtime::DriverStatus::kNotActive;
  bump(writes_);
  const double e = std::isfinite(command.e) ? command.e : 0.0;
  commands_.publish(Command{e, ++command_seq_, held_.seq});
  return connected_.load(std::memory_order_acquire) ? runtime::DriverStatus::kOk
                                                    : runtime::DriverStatus::kDisconnected;
}

runtime::DriverCounters ModbusDriver::counters() const noexcept {
  runtime::DriverCounters c;
  c.reads = reads_.load(std::memory_order_relaxed);
  c.writes = writes_.load(std::memory_order_relaxed);
  c.stale = stale_.load(std::memory_order_relaxed);
  c.errors = errors_.load(std::memory_order_relaxed);
  c.timeouts = timeouts_.load(std::memory_order_relaxed);
  c.retries = retries_.load(std::memory_order_relaxed);
  c.reconnects = reconnects_.load(std::memory_order_relaxed);
  c.bad_data = bad_data_.load(std::memory_order_relaxed);
  c.device_faults = device_faults_.load(std::memory_order_relaxed);
  c.crc_errors = crc_errors_.load(std::memory_order_relaxed);
  // The bus thread's figures that are counts (BusStats), and exceptions under their own name.
  c.add_event("exception_responses", c.device_faults);
  c.add_event("polls", polls_.load(std::memory_order_relaxed));
  c.add_event("late_commands", late_commands_.load(std::memory_order_relaxed));
  c.add_event("missed_deadlines", missed_deadlines_.load(std::memory_order_relaxed));
  return c;
}

BusStats ModbusDriver::bus_stats() const noexcept {
  BusStats s;
  s.polls = polls_.load(std::memory_order_relaxed);
  s.poll_ns_sum = poll_ns_sum_.load(std::memory_order_relaxed);
  s.poll_ns_max = poll_ns_max_.load(std::memory_order_relaxed);
  s.latencies = latencies_.load(std::memory_order_relaxed);
  s.latency_ns_sum = latency_ns_sum_.load(std::memory_order_relaxed);
  s.latency_ns_max = latency_ns_max_.load(std::memory_order_relaxed);
  s.late_commands = late_commands_.load(std::memory_order_relaxed);
  s.missed_deadlines = missed_deadlines_.load(std::memory_order_relaxed);
  return s;
}

void ModbusDriver::sleep_for_ns(std::int64_t ns) const noexcept {
  // In slices, so that deactivate() never waits for a long back-off.
  const std::int64_t end = runtime::monotonic_ns() + ns;
  for (std::int64_t t = runtime::monotonic_ns(); t < end && !stop_.load();
       t = runtime::monotonic_ns()) {
    runtime::sleep_until(std::min(end, t + 10'000'000));
  }
}

bool ModbusDriver::connect_bus() noexcept {
  if (modbus_connect(ctx_) != 0) {
    bump(errors_);
    return false;
  }
  if (ever_connected_) bump(reconnects_);
  ever_connected_ = true;
  failures_in_row_ = 0;
  written_seq_ = 0;  // write the newest command on the new link
  connected_.store(true, std::memory_order_release);
  return true;
}

void ModbusDriver::disconnect_bus() noexcept {
  connected_.store(false, std::memory_order_release);
  modbus_close(ctx_);
}

bool ModbusDriver::count_failure(int err) noexcept {
  bump(errors_);
  ++failures_in_row_;
  if (err >= EMBXILFUN && err <= EMBXGTAR) {
    bump(device_faults_);  // the device answered with an exception: the link is fine
    return true;
  }
  if (err == ETIMEDOUT) {
    bump(timeouts_);
    // A late answer would be taken for the next one's: drop what has arrived.
    modbus_flush(ctx_);
    return failures_in_row_ < config_.reconnect_after_failures;
  }
  if (err == EMBBADCRC) bump(crc_errors_);
  if (err == EMBBADCRC || err == EMBBADDATA || err == EMBBADEXC || err == EMBUNKEXC ||
      err == EMBMDATA || err == EMBBADSLAVE) {
    bump(bad_data_);
    modbus_flush(ctx_);
    // A TCP stream that carried garbage has lost its framing: start a fresh connection.
    return config_.transport == Transport::kRtu &&
           failures_in_row_ < config_.reconnect_after_failures;
  }
  return false;  // the link itself failed (reset, refused, closed)
}

bool ModbusDriver::poll_inputs(std::uint64_t seq) noexcept {
  const std::int64_t start = runtime::monotonic_ns();
  for (std::size_t i = 0; i < blocks_.size(); ++i) {
    const Block& b = blocks_[i];
    if (!b.used) continue;
    std::uint16_t* dest = words_.data() + i * kMaxReadRegisters;
    const int rc = static_cast<Function>(i) == Function::kInput
                       ? modbus_read_input_registers(ctx_, b.first, b.count, dest)
                       : modbus_read_registers(ctx_, b.first, b.count, dest);
    if (rc != b.count) {
      if (rc >= 0) errno = EMBMDATA;
      return false;
    }
  }
  const std::int64_t done = runtime::monotonic_ns();
  Sample s;
  s.seq = seq;
  s.received_ns = done;
  s.in.timestamp_ns = done;
  const RegisterMap& m = config_.registers;
  const auto value = [&](const RegisterSpec& spec, double& out) {
    if (!spec.enabled) return;
    const auto table = static_cast<std::size_t>(spec.function);
    const std::span<const std::uint16_t> words(
        words_.data() + table * kMaxReadRegisters +
            static_cast<std::size_t>(spec.address - blocks_[table].first),
        static_cast<std::size_t>(word_count(spec.type)));
    const Decoded d = decode(spec, words);
    out = d.value;
    if (d.status != DecodeStatus::kOk) s.bad = true;
  };
  value(m.e, s.in.e);
  value(m.d, s.in.d);
  value(m.s_ref, s.in.s_ref);
  value(m.t_ref, s.in.t_ref);
  value(m.temp, s.in.temp_ref);
  if (m.status.enabled) {
    double status = 0.0;
    value(m.status, status);
    s.in.device_status = std::isfinite(status) && status >= 0.0 && status <= 65535.0
                             ? static_cast<std::uint16_t>(status)
                             : std::uint16_t{0xffff};
  }
  if (s.bad) bump(bad_data_);
  samples_.publish(s);
  published_seq_ = seq;
  published_ns_ = done;
  bump(polls_);
  const auto took = static_cast<std::uint64_t>(done - start);
  poll_ns_sum_.fetch_add(took, std::memory_order_relaxed);
  update_max(poll_ns_max_, took);
  poll_hist_.record(done - start);
  return true;
}

bool ModbusDriver::write_command(const Command& c) noexcept {
  std::array<std::uint16_t, 2> words{};
  const RegisterSpec& spec = config_.registers.command;
  if (!encode(spec, c.e, words)) {
    // Out of the register's range: written as the nearest representable bound is a wrong
    // number, so the safe value goes out instead and the fault is counted.
    bump(bad_data_);
    if (!encode(spec, 0.0, words)) return true;
  }
  if (modbus_write_registers(ctx_, spec.address, word_count(spec.type), words.data()) < 0) {
    return false;
  }
  written_seq_ = c.seq;
  if (c.sample_seq == published_seq_ && published_seq_ != 0) {
    const auto latency = static_cast<std::uint64_t>(runtime::monotonic_ns() - published_ns_);
    bump(latencies_);
    latency_ns_sum_.fetch_add(latency, std::memory_order_relaxed);
    update_max(latency_ns_max_, latency);
    latency_hist_.record(static_cast<std::int64_t>(latency));
  } else {
    bump(late_commands_);
  }
  return true;
}

void ModbusDriver::run_bus() noexcept {
  // Sleeps end when asked (1 us slack instead of the default 50 us of a normal thread): the
  // wait for the loop's command is in the read-to-write latency.
  static_cast<void>(prctl(PR_SET_TIMERSLACK, 1000UL, 0UL, 0UL, 0UL));
  auto backoff = static_cast<std::int64_t>(config_.reconnect_min_s * 1e9);
  const auto backoff_max = static_cast<std::int64_t>(config_.reconnect_max_s * 1e9);
  std::uint64_t seq = 0;
  std::int64_t next = runtime::monotonic_ns();
  while (!stop_.load()) {
    if (!connected_.load(std::memory_order_relaxed)) {
      if (!connect_bus()) {
        modbus_close(ctx_);
        sleep_for_ns(backoff);
        backoff = std::min(2 * backoff, backoff_max);
        continue;
      }
      backoff = static_cast<std::int64_t>(config_.reconnect_min_s * 1e9);
      next = runtime::monotonic_ns();
    }
    const std::int64_t now = runtime::monotonic_ns();
    if (now - next > period_ns_) {
      bump(missed_deadlines_);
      next = now;
    }
    runtime::sleep_until(next);
    next += period_ns_;
    if (failures_in_row_ > 0) bump(retries_);

    bool ok = poll_inputs(++seq);
    if (ok) {
      // Wait (a short sleep at a time) for the loop's command computed from this sample.
      const std::int64_t wait_end = published_ns_ + period_ns_ / 2;
      Command c;
      while (!stop_.load() && (!commands_.try_read(c) || c.sample_seq < published_seq_) &&
             runtime::monotonic_ns() < wait_end) {
        runtime::sleep_until(runtime::monotonic_ns() + kCommandPollNs);
      }
      if (commands_.try_read(c) && c.seq != 0 && c.seq != written_seq_) ok = write_command(c);
    }
    if (ok) {
      failures_in_row_ = 0;
    } else if (!count_failure(errno)) {
      disconnect_bus();
    }
  }
  if (connected_.load(std::memory_order_relaxed)) {
    Command c;
    if (commands_.try_read(c) && c.seq != written_seq_) static_cast<void>(write_command(c));
  }
  disconnect_bus();
}

}  // namespace selfsense::drivers::modbus
