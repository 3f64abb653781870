#include "selfsense/drivers/can/can_driver.hpp"

#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <pthread.h>
#include <sched.h>
#include <sys/eventfd.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <utility>
#include <vector>

#include "selfsense/base/errno_text.hpp"
#include "selfsense/runtime/monotonic.hpp"

namespace selfsense::drivers::can {
namespace {

canid_t wire_id(const FrameId& f) noexcept {
  return f.extended ? (f.id & CAN_EFF_MASK) | CAN_EFF_FLAG : f.id & CAN_SFF_MASK;
}

std::string errno_text(const char* what) {
  return std::string(what) + ": " + base::errno_text(errno);
}

void bump(std::atomic<std::uint64_t>& c) noexcept {
  c.fetch_add(1, std::memory_order_relaxed);
}

constexpr int kPollTimeoutMs = 50;  // how soon the bus thread sees a stop request
constexpr int kReadAttempts = 4;    // LatestValue::try_read attempts per read()

}  // namespace

CanDriver::CanDriver(CanConfig config) : config_(std::move(config)) {}

CanDriver::~CanDriver() {
  deactivate();
}

bool CanDriver::configure(const runtime::DriverSetup& setup, std::string* why) {
  const auto fail = [why](const std::string& m) {
    if (why != nullptr) *why = m;
    return false;
  };
  if (!(setup.sample_time > 0.0)) return fail("can: the loop's sample time must be > 0");
  if (!config_.e.present || !config_.d.present || !config_.command.present) {
    return fail("driver.signals: e, d and command are required");
  }
  const std::array<std::pair<const SignalConfig*, double runtime::InputSample::*>, 5> inputs{
      {{&config_.e, &runtime::InputSample::e},
       {&config_.d, &runtime::InputSample::d},
       {&config_.s_ref, &runtime::InputSample::s_ref},
       {&config_.t_ref, &runtime::InputSample::t_ref},
       {&config_.temp, &runtime::InputSample::temp_ref}}};
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    const auto& [signal, field] = inputs.at(i);
    slots_.at(i) = Slot{*signal, signal->present ? bytes_needed(signal->signal) : 0, field};
  }
  rx_timeout_ns_ = static_cast<std::int64_t>(std::llround(config_.rx_timeout_ms * 1e6));
  temp_timeout_ns_ = static_cast<std::int64_t>(std::llround(config_.temp_timeout_ms * 1e6));
  tx_ = canfd_frame{};
  tx_.can_id = wire_id(config_.command.frame);
  const std::size_t bytes = config_.frame_length(bytes_needed(config_.command.signal));
  tx_.len = static_cast<std::uint8_t>(bytes);
  tx_size_ = config_.fd ? CANFD_MTU : CAN_MTU;
  if (config_.fd) tx_.flags = CANFD_BRS;
  configured_ = true;
  return true;
}

bool CanDriver::activate(std::string* why) {
  const auto fail = [this, why](const std::string& m) {
    if (why != nullptr) *why = m;
    if (socket_ >= 0) ::close(socket_);
    socket_ = -1;
    if (wake_fd_ >= 0) ::close(wake_fd_);
    wake_fd_ = -1;
    return false;
  };
  if (!configured_) return fail("can: activate() before configure()");
  if (active_) return true;
  socket_ = ::socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (socket_ < 0) {
    return fail(errno_text("can: socket(PF_CAN, SOCK_RAW, CAN_RAW)") +
                " (a kernel without SocketCAN? modprobe can can_raw)");
  }
  ifreq ifr{};
  static_cast<void>(
      std::snprintf(ifr.ifr_name, sizeof(ifr.ifr_name), "%s", config_.interface.c_str()));
  if (::ioctl(socket_, SIOCGIFINDEX, &ifr) < 0) {
    return fail("driver.interface: " + config_.interface + ": " + base::errno_text(errno));
  }
  const int index = ifr.ifr_ifindex;
  if (config_.fd) {
    if (::ioctl(socket_, SIOCGIFMTU, &ifr) < 0) {
      return fail(errno_text("driver.interface: SIOCGIFMTU"));
    }
    if (ifr.ifr_mtu != static_cast<int>(CANFD_MTU)) {
      return fail("driver.fd: " + config_.interface + " has MTU " + std::to_string(ifr.ifr_mtu) +
                  ", CAN FD needs " + std::to_string(CANFD_MTU) + " (ip link set " +
                  config_.interface + " mtu 72)");
    }
    const int on = 1;
    if (::setsockopt(socket_, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof(on)) < 0) {
      return fail(errno_text("driver.fd: setsockopt(CAN_RAW_FD_FRAMES)"));
    }
  }
  std::vector<can_filter> filters;
  for (const FrameLayout& f : config_.input_frames()) {
    filters.push_back({wire_id(f.id), (f.id.extended ? CAN_EFF_MASK : CAN_SFF_MASK) | CAN_EFF_FLAG |
                                          CAN_RTR_FLAG});
  }
  if (::setsockopt(socket_, SOL_CAN_RAW, CAN_RAW_FILTER, filters.data(),
                   static_cast<socklen_t>(filters.size() * sizeof(can_filter))) < 0) {
    return fail(errno_text("can: setsockopt(CAN_RAW_FILTER)"));
  }
  const can_err_mask_t errors = config_.error_frames ? CAN_ERR_MASK : 0U;
  if (::setsockopt(socket_, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &errors, sizeof(errors)) < 0) {
    return fail(errno_text("driver.error_frames: setsockopt(CAN_RAW_ERR_FILTER)"));
  }
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = index;
  if (::bind(socket_, reinterpret_cast<const sockaddr*>(&addr), sizeof(addr)) < 0) {
    return fail("driver.interface: bind to " + config_.interface + ": " + base::errno_text(errno));
  }
  wake_fd_ = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (wake_fd_ < 0) return fail(errno_text("can: eventfd"));
  building_ = CanInputs{};
  latest_.publish(building_);
  last_ = CanInputs{};
  last_sequence_ = 0;
  repeats_ = 0;
  bus_off_.store(false, std::memory_order_relaxed);
  error_passive_.store(false, std::memory_order_relaxed);
  send_failed_.store(false, std::memory_order_relaxed);
  stop_.store(false, std::memory_order_relaxed);
  command_seq_ = 0;
  sent_seq_ = 0;
  command_.publish(CanCommand{});
  activated_ns_ = runtime::monotonic_ns();
  read_ns_ = activated_ns_;
  thread_ = std::thread([this] { bus_loop(); });
  priority_granted_ = true;
  if (config_.priority > 0) {
    sched_param param{};
    param.sched_priority = config_.priority;
    priority_granted_ = pthread_setschedparam(thread_.native_handle(), SCHED_FIFO, &param) == 0;
  }
  active_ = true;
  return true;
}

void CanDriver::bus_loop() noexcept {
  canfd_frame frame{};
  while (!stop_.load(std::memory_order_relaxed)) {
    std::array<pollfd, 2> p{{{wake_fd_, POLLIN, 0}, {socket_, POLLIN, 0}}};
    if (::poll(p.data(), p.size(), kPollTimeoutMs) <= 0) continue;
    if ((p[0].revents & POLLIN) != 0) {
      std::uint64_t wakes = 0;
      static_cast<void>(::read(wake_fd_, &wakes, sizeof(wakes)));
      send_command();
    }
    if ((p[1].revents & POLLIN) == 0) continue;
    for (;;) {
      const ssize_t n = ::recv(socket_, &frame, sizeof(frame), MSG_DONTWAIT);
      if (n < 0) break;
      const std::int64_t t = runtime::monotonic_ns();
      if (n != static_cast<ssize_t>(CAN_MTU) && n != static_cast<ssize_t>(CANFD_MTU)) {
        bump(n_.bad_data);
        continue;
      }
      if (n == static_cast<ssize_t>(CAN_MTU)) frame.flags = 0;  // a classic frame's padding
      on_frame(frame, t);
    }
  }
}

void CanDriver::on_frame(const canfd_frame& frame, std::int64_t now) noexcept {
  bump(n_.rx_frames);
  if ((frame.can_id & CAN_ERR_FLAG) != 0U) {
    bump(n_.error_frames);
    if ((frame.can_id & CAN_ERR_BUSOFF) != 0U && !bus_off_.load(std::memory_order_relaxed)) {
      bus_off_seen_.store(false, std::memory_order_relaxed);
      bus_off_.store(true, std::memory_order_relaxed);
      bump(n_.bus_off);
    }
    if ((frame.can_id & CAN_ERR_RESTARTED) != 0U && bus_off_.exchange(false)) bump(n_.reconnects);
    // A protocol violation located in the CRC field: the controller saw a frame's CRC fail.
    if ((frame.can_id & CAN_ERR_PROT) != 0U && frame.len > 3 &&
        (frame.data[3] == CAN_ERR_PROT_LOC_CRC_SEQ || frame.data[3] == CAN_ERR_PROT_LOC_CRC_DEL)) {
      bump(n_.crc_errors);
    }
    if ((frame.can_id & CAN_ERR_CRTL) != 0U && frame.len > 1) {
      const std::uint8_t ctrl = frame.data[1];
      if ((ctrl & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) != 0U) {
        error_passive_.store(true, std::memory_order_relaxed);
      }
      if ((ctrl & CAN_ERR_CRTL_ACTIVE) != 0U)
        error_passive_.store(false, std::memory_order_relaxed);
    }
    return;
  }
  if ((frame.can_id & CAN_RTR_FLAG) != 0U) return;
  const bool extended = (frame.can_id & CAN_EFF_FLAG) != 0U;
  const FrameId id{frame.can_id & (extended ? CAN_EFF_MASK : CAN_SFF_MASK), extended};
  const std::span<const std::uint8_t> data(frame.data, frame.len);
  bool matched = false;
  for (const Slot& s : slots_) {
    if (!s.config.present || !(s.config.frame == id)) continue;
    if (frame.len < s.bytes) {
      bump(n_.bad_data);  // the whole frame is dropped
      return;
    }
    matched = true;
  }
  if (!matched) return;
  for (const Slot& s : slots_) {
    if (!s.config.present || !(s.config.frame == id)) continue;
    building_.sample.*s.field = decode(data, s.config.signal);
    if (s.field == &runtime::InputSample::e) building_.e_ns = now;
    if (s.field == &runtime::InputSample::d) building_.d_ns = now;
    if (s.field == &runtime::InputSample::temp_ref) building_.temp_ns = now;
  }
  ++building_.sequence;
  building_.newest_ns = now;
  building_.sample.timestamp_ns = now;
  // An input frame after the loop has seen the bus-off: the bus works again.
  if (bus_off_.load(std::memory_order_relaxed) && bus_off_seen_.load(std::memory_order_relaxed)) {
    bus_off_.store(false, std::memory_order_relaxed);
    bump(n_.reconnects);
  }
  latest_.publish(building_);
}

runtime::DriverStatus CanDriver::read(runtime::InputSample& out) noexcept {
  if (!active_) return runtime::DriverStatus::kNotActive;
  bump(n_.reads);
  const std::int64_t now = runtime::monotonic_ns();
  read_ns_ = now;
  CanInputs in{};
  for (int i = 0; i < kReadAttempts; ++i) {
    if (latest_.try_read(in)) {
      last_ = in;
      break;
    }
  }
  out = last_.sample;
  if (config_.temp.present && (last_.temp_ns == 0 || now - last_.temp_ns > temp_timeout_ns_)) {
    out.temp_ref = runtime::InputSample::kNone;
    bump(n_.temp_timeouts);
  }
  const bool bus_off = bus_off_.load(std::memory_order_relaxed);
  out.device_status = static_cast<std::uint16_t>(
      (bus_off ? kStatusBusOff : 0U) |
      (error_passive_.load(std::memory_order_relaxed) ? kStatusErrorPassive : 0U));
  read_ok_ = false;
  if (bus_off) {
    bus_off_seen_.store(true, std::memory_order_relaxed);
    bump(n_.disconnected);
    return runtime::DriverStatus::kDisconnected;
  }
  const std::int64_t oldest = std::min(last_.e_ns, last_.d_ns);
  if (oldest == 0 || now - oldest > rx_timeout_ns_) {
    bump(n_.timeouts);
    return runtime::DriverStatus::kTimeout;
  }
  if (last_.sequence == last_sequence_) {
    ++repeats_;
  } else {
    repeats_ = 0;
    last_sequence_ = last_.sequence;
  }
  if (config_.stale_cycles > 0 && repeats_ >= config_.stale_cycles) {
    bump(n_.stale);
    return runtime::DriverStatus::kStale;
  }
  read_ok_ = true;
  return runtime::DriverStatus::kOk;
}

runtime::DriverStatus CanDriver::write(const runtime::OutputCommand& command) noexcept {
  if (!active_) return runtime::DriverStatus::kNotActive;
  const std::int64_t now = runtime::monotonic_ns();
  command_.publish(CanCommand{command.e, ++command_seq_, read_ok_ ? last_.newest_ns : 0, now});
  // Wakes the bus thread: adds 1 to the eventfd's counter. Never blocks (non-blocking; the
  // counter would need 2^64 - 2 unread wakes to be full).
  const std::uint64_t one = 1;
  static_cast<void>(::write(wake_fd_, &one, sizeof(one)));
  read_to_write_.record(now - read_ns_);
  return send_failed_.load(std::memory_order_relaxed) ? runtime::DriverStatus::kDisconnected
                                                      : runtime::DriverStatus::kOk;
}

bool CanDriver::send_frame(double e) noexcept {
  const std::span<std::uint8_t> data(tx_.data, tx_.len);
  const EncodeResult r = encode(data, config_.command.signal, e);
  if (r == EncodeResult::kNotFinite) {
    static_cast<void>(encode(data, config_.command.signal, 0.0));
  }
  if (r != EncodeResult::kOk) bump(n_.saturated);
  const ssize_t n = ::send(socket_, &tx_, tx_size_, MSG_DONTWAIT);
  if (n == static_cast<ssize_t>(tx_size_)) {
    bump(n_.writes);
    send_failed_.store(false, std::memory_order_relaxed);
    return true;
  }
  if (n < 0 && (errno == EAGAIN || errno == ENOBUFS)) {
    bump(n_.retries);  // the TX queue is full; the loop's next command goes out instead
    return false;
  }
  bump(n_.tx_errors);
  send_failed_.store(true, std::memory_order_relaxed);
  return false;
}

void CanDriver::send_command() noexcept {
  CanCommand c{};
  if (!command_.try_read(c)) {
    // write() is publishing a newer command; its wake-up follows.
    return;
  }
  if (c.seq == 0 || c.seq == sent_seq_) return;
  if (c.seq > sent_seq_ + 1 && sent_seq_ != 0) n_.superseded.fetch_add(c.seq - sent_seq_ - 1);
  sent_seq_ = c.seq;
  if (!send_frame(c.e)) return;
  const std::int64_t now = runtime::monotonic_ns();
  tx_latency_.record(now - c.handed_ns);
  if (c.inputs_ns != 0) rx_to_tx_.record(now - c.inputs_ns);
}

void CanDriver::deactivate() noexcept {
  if (!active_) return;
  // The bus thread stops, then the safe output (E = 0) goes on the bus and the socket closes.
  stop_.store(true, std::memory_order_relaxed);
  const std::uint64_t one = 1;
  static_cast<void>(::write(wake_fd_, &one, sizeof(one)));
  if (thread_.joinable()) thread_.join();
  static_cast<void>(send_frame(0.0));
  ::close(socket_);
  socket_ = -1;
  ::close(wake_fd_);
  wake_fd_ = -1;
  active_ = false;
  // Not real-time here: the loop has stopped. One line for the log (and the measured figures).
  const runtime::DriverCounters c = counters();
  static_cast<void>(std::fprintf(
      stderr,
      "can: %s: rx_to_tx_us p50=%.0f p99=%.0f max=%.0f read_to_write_us p50=%.1f p99=%.1f "
      "max=%.1f (n=%lld) handover_to_send_us p50=%.1f p99=%.1f max=%.1f; reads=%llu writes=%llu "
      "errors=%llu timeouts=%llu stale=%llu "
      "bad_data=%llu retries=%llu reconnects=%llu device_faults=%llu\n",
      config_.interface.c_str(), static_cast<double>(rx_to_tx_.percentile_ns(0.5)) / 1e3,
      static_cast<double>(rx_to_tx_.percentile_ns(0.99)) / 1e3,
      static_cast<double>(rx_to_tx_.max_ns()) / 1e3,
      static_cast<double>(read_to_write_.percentile_ns(0.5)) / 1e3,
      static_cast<double>(read_to_write_.percentile_ns(0.99)) / 1e3,
      static_cast<double>(read_to_write_.max_ns()) / 1e3,
      static_cast<long long>(read_to_write_.count()),
      static_cast<double>(tx_latency_.percentile_ns(0.5)) / 1e3,
      static_cast<double>(tx_latency_.percentile_ns(0.99)) / 1e3,
      static_cast<double>(tx_latency_.max_ns()) / 1e3, static_cast<unsigned long long>(c.reads),
      static_cast<unsigned long long>(c.writes), static_cast<unsigned long long>(c.errors),
      static_cast<unsigned long long>(c.timeouts), static_cast<unsigned long long>(c.stale),
      static_cast<unsigned long long>(c.bad_data), static_cast<unsigned long long>(c.retries),
      static_cast<unsigned long long>(c.reconnects),
      static_cast<unsigned long long>(c.device_faults)));
}

runtime::DriverCounters CanDriver::counters() const noexcept {
  const auto get = [](const std::atomic<std::uint64_t>& a) {
    return a.load(std::memory_order_relaxed);
  };
  runtime::DriverCounters c;
  c.reads = get(n_.reads);
  c.writes = get(n_.writes);
  c.errors = get(n_.error_frames) + get(n_.tx_errors);
  c.timeouts = get(n_.timeouts) + get(n_.disconnected);
  c.stale = get(n_.stale);
  c.bad_data = get(n_.bad_data);
  c.retries = get(n_.retries);
  c.reconnects = get(n_.reconnects);
  c.device_faults = get(n_.bus_off);
  c.crc_errors = get(n_.crc_errors);
  // The parts of the sums above, and what CanCounters keeps, under their own names.
  c.add_event("rx_frames", get(n_.rx_frames));
  c.add_event("error_frames", get(n_.error_frames));
  c.add_event("tx_errors", get(n_.tx_errors));
  c.add_event("tx_queue_full", get(n_.retries));
  c.add_event("rx_timeouts", get(n_.timeouts));
  c.add_event("bus_off_reads", get(n_.disconnected));
  c.add_event("bus_off", get(n_.bus_off));
  c.add_event("command_saturated", get(n_.saturated));
  c.add_event("commands_superseded", get(n_.superseded));
  c.add_event("temp_timeouts", get(n_.temp_timeouts));
  return c;
}

CanCounters CanDriver::can_counters() const noexcept {
  CanCounters c;
  c.rx_frames = n_.rx_frames.load(std::memory_order_relaxed);
  c.error_frames = n_.error_frames.load(std::memory_order_relaxed);
  c.tx_frames = n_.writes.load(std::memory_order_relaxed);
  c.command_saturated = n_.saturated.load(std::memory_order_relaxed);
  c.commands_superseded = n_.superseded.load(std::memory_order_relaxed);
  return c;
}

}  // namespace selfsense::drivers::can
