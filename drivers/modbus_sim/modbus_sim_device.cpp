// The simulated transducer as a Modbus server (TCP or RTU) over libmodbus, with the default
// register map of the Modbus driver and the stack's temperature (served_register_map(),
// include/selfsense/drivers/modbus/register_map.hpp, docs/drivers/modbus.md).
//
// One thread: ppoll() on the bus descriptors until the next update deadline (absolute, on
// CLOCK_MONOTONIC). Each update writes the command register's value to the simulated amplifier
// (zero-order hold, like a DAC), advances the plant by one device period, and stores the
// measured E, D, the true S, T, the plant's status bits and temperature in the input registers.
// Requests are answered between updates from the register tables; a register outside the map gets
// the exception response "illegal data address". SIGINT and SIGTERM end it with status 0.
#include "selfsense/drivers/modbus_sim/modbus_sim_device.hpp"

#include <modbus.h>
#include <netinet/in.h>
#include <poll.h>
#include <sched.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "selfsense/base/errno_text.hpp"
#include "selfsense/drivers/modbus/register_map.hpp"
#include "selfsense/drivers/sim/simulated_transducer.hpp"
#include "selfsense/plant_io/plant_yaml.hpp"
#include "selfsense/runtime/monotonic.hpp"

namespace selfsense::drivers::modbus_sim {
namespace {

namespace mb = modbus;

volatile std::sig_atomic_t g_stop = 0;  // NOLINT: written by the signal handler only

void on_signal(int /*signal*/) {
  g_stop = 1;
}

// SIGINT and SIGTERM blocked except inside ppoll(), so a signal can only end a wait.
class StopSignals final {
 public:
  StopSignals() {
    g_stop = 0;
    struct sigaction sa {};
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);
    sigset_t block;
    sigemptyset(&block);
    sigaddset(&block, SIGINT);
    sigaddset(&block, SIGTERM);
    sigprocmask(SIG_BLOCK, &block, &wait_mask_);
    sigdelset(&wait_mask_, SIGINT);
    sigdelset(&wait_mask_, SIGTERM);
  }
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;
  StopSignals(StopSignals&&) = delete;
  StopSignals& operator=(StopSignals&&) = delete;
  ~StopSignals() = default;
  [[nodiscard]] const sigset_t* wait_mask() const noexcept { return &wait_mask_; }

 private:
  sigset_t wait_mask_{};
};

struct MappingDeleter {
  void operator()(modbus_mapping_t* m) const noexcept { modbus_mapping_free(m); }
};
struct ContextDeleter {
  void operator()(modbus_t* c) const noexcept {
    modbus_close(c);
    modbus_free(c);
  }
};

// The register span [first, end) of one table over the map's entries.
struct Span {
  int first{0};
  int end{0};
  void add(const mb::RegisterSpec& s) {
    if (!s.enabled) return;
    if (first == end) {
      first = s.address;
      end = s.address + mb::word_count(s.type);
      return;
    }
    first = std::min(first, s.address);
    end = std::max(end, s.address + mb::word_count(s.type));
  }
};

// The plant behind the register tables.
class Device final {
 public:
  Device(const ModbusSimDeviceOptions& options, mb::RegisterMap map)
      : map_(map),
        transducer_(plant::load_plant_file(options.plant).plant),
        period_ns_(std::llround(1e9 / options.rate_hz)) {
    std::string why;
    if (!(options.rate_hz > 0.0) || !transducer_.configure({1.0 / options.rate_hz}, &why)) {
      throw std::invalid_argument("--rate " + std::to_string(options.rate_hz) + ": " + why);
    }
    if (!transducer_.activate(&why)) throw std::runtime_error(why);
    Span holding;
    Span input;
    for (const mb::RegisterSpec* s : map_.inputs())
      (s->function == mb::Function::kInput ? input : holding).add(*s);
    holding.add(map_.command);
    mapping_.reset(modbus_mapping_new_start_address(
        0, 0, 0, 0, static_cast<unsigned>(holding.first),
        static_cast<unsigned>(holding.end - holding.first), static_cast<unsigned>(input.first),
        static_cast<unsigned>(input.end - input.first)));
    if (!mapping_) throw std::runtime_error("sim-device: no memory for the register tables");
    update();  // the first sample is there before the first request
  }

  [[nodiscard]] modbus_mapping_t* mapping() const noexcept { return mapping_.get(); }
  [[nodiscard]] std::int64_t period_ns() const noexcept { return period_ns_; }
  [[nodiscard]] std::uint64_t updates() const noexcept { return updates_; }
  [[nodiscard]] std::uint64_t bad_commands() const noexcept { return bad_commands_; }
  [[nodiscard]] double skipped_s() const noexcept {
    return 1e-9 * static_cast<double>(skipped_ns_);
  }
  void skip(std::int64_t ns) noexcept { skipped_ns_ += ns; }

  void update() {
    const std::span<std::uint16_t> command = words(map_.command);
    const mb::Decoded c = mb::decode(map_.command, command);
    if (c.status != mb::DecodeStatus::kOk) ++bad_commands_;
    static_cast<void>(transducer_.write({c.status == mb::DecodeStatus::kOk ? c.value : 0.0}));
    runtime::InputSample in;
    static_cast<void>(transducer_.read(in));
    store(map_.e, in.e);
    store(map_.d, in.d);
    store(map_.s_ref, in.s_ref);
    store(map_.t_ref, in.t_ref);
    store(map_.status, in.device_status);
    store(map_.temp, in.temp_ref);
    ++updates_;
  }

 private:
  std::span<std::uint16_t> words(const mb::RegisterSpec& s) const noexcept {
    const bool input = s.function == mb::Function::kInput;
    std::uint16_t* table = input ? mapping_->tab_input_registers : mapping_->tab_registers;
    const int start = input ? mapping_->start_input_registers : mapping_->start_registers;
    return {table + (s.address - start), static_cast<std::size_t>(mb::word_count(s.type))};
  }
  void store(const mb::RegisterSpec& s, double value) {
    if (!s.enabled) return;
    if (!mb::encode(s, value, words(s)) && s.type == mb::RegisterType::kFloat32) {
      // NaN or beyond float range: the device says so in the value (a quiet NaN).
      const std::span<std::uint16_t> w = words(s);
      const bool high_first = s.word_order == mb::WordOrder::kHighFirst;
      w[0] = high_first ? 0x7fc0 : 0x0000;
      w[1] = high_first ? 0x0000 : 0x7fc0;
    }
  }

  mb::RegisterMap map_;
  drivers::SimulatedTransducer transducer_;
  std::int64_t period_ns_;
  std::unique_ptr<modbus_mapping_t, MappingDeleter> mapping_{};
  std::uint64_t updates_{0};
  std::uint64_t bad_commands_{0};
  std::int64_t skipped_ns_{0};
};

void set_priority(int priority) {
  if (priority <= 0) return;
  sched_param param{};
  param.sched_priority = priority;
  if (sched_setscheduler(0, SCHED_FIFO, &param) != 0) {
    static_cast<void>(
        std::fprintf(stderr, "sim-device: warning: SCHED_FIFO %d refused (%s); normal scheduling\n",
                     priority, base::errno_text(errno).c_str()));
  }
}

struct ServerCounts {
  std::uint64_t requests{0};
  std::uint64_t errors{0};
  std::uint64_t connections{0};
};

// Waits for bus traffic until the next device update; true when the update is due.
// Returns false with g_stop set when a signal arrived.
bool wait_until(std::vector<pollfd>& fds, std::int64_t deadline, const StopSignals& signals) {
  const std::int64_t left = std::max<std::int64_t>(0, deadline - runtime::monotonic_ns());
  timespec ts{static_cast<time_t>(left / 1'000'000'000), static_cast<long>(left % 1'000'000'000)};
  for (pollfd& p : fds)
    p.revents = 0;
  const int rc = ppoll(fds.data(), fds.size(), &ts, signals.wait_mask());
  if (rc < 0 && errno != EINTR)
    throw std::runtime_error(std::string("ppoll: ") + base::errno_text(errno));
  return rc <= 0;
}

void finish(const Device& device, const ServerCounts& counts) {
  static_cast<void>(std::printf(
      "sim-device: stopped after %llu updates, %llu requests, %llu connections, %llu bus errors, "
      "%llu bad commands, %.3f s not replayed\n",
      static_cast<unsigned long long>(device.updates()),
      static_cast<unsigned long long>(counts.requests),
      static_cast<unsigned long long>(counts.connections),
      static_cast<unsigned long long>(counts.errors),
      static_cast<unsigned long long>(device.bad_commands()), device.skipped_s()));
  static_cast<void>(std::fflush(stdout));
}

// Runs every update that is due and returns the next deadline. A physical transducer does not
// pause when its server is descheduled: the plant catches up on the periods it missed, with the
// command held, so its clock stays the wall clock the daemon's model steps by. Beyond one second
// behind it starts again from now (the missed time is counted, not replayed).
std::int64_t run_due_updates(Device& device, std::int64_t next) {
  const std::int64_t period = device.period_ns();
  const std::int64_t now = runtime::monotonic_ns();
  if (now - next > 1'000'000'000) {
    device.skip(now - next);
    next = now;
  }
  while (next <= now) {
    device.update();
    next += period;
  }
  return next;
}

}  // namespace

std::pair<std::string, int> parse_host_port(const std::string& text) {
  const std::size_t colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == text.size()) {
    throw std::invalid_argument("--modbus-tcp: '" + text + "' is not HOST:PORT");
  }
  std::size_t used = 0;
  const int port = std::stoi(text.substr(colon + 1), &used);
  if (used != text.size() - colon - 1 || port < 0 || port > 65535) {
    throw std::invalid_argument("--modbus-tcp: port '" + text.substr(colon + 1) +
                                "' must be within [0, 65535]");
  }
  return {text.substr(0, colon), port};
}

int serve_modbus_tcp(const ModbusSimDeviceOptions& options, const std::string& host, int port) {
  const StopSignals signals;
  Device device(options, mb::served_register_map());
  set_priority(options.priority);
  const std::unique_ptr<modbus_t, ContextDeleter> ctx(
      modbus_new_tcp_pi(host.c_str(), std::to_string(port).c_str()));
  if (!ctx) throw std::runtime_error("--modbus-tcp: " + std::string(modbus_strerror(errno)));
  modbus_set_slave(ctx.get(), options.unit_id);
  // A client that stops mid-frame holds the server (and the plant's updates) this long at most.
  modbus_set_byte_timeout(ctx.get(), 0, 10'000);
  const int listener = modbus_tcp_pi_listen(ctx.get(), 8);
  if (listener < 0) {
    throw std::runtime_error("--modbus-tcp " + host + ":" + std::to_string(port) + ": " +
                             modbus_strerror(errno));
  }
  sockaddr_storage bound{};
  socklen_t length = sizeof(bound);
  getsockname(listener, reinterpret_cast<sockaddr*>(&bound), &length);  // NOLINT: sockets API
  const int actual = ntohs(reinterpret_cast<sockaddr_in*>(&bound)->sin_port);  // NOLINT
  static_cast<void>(std::printf("sim-device: modbus-tcp on %s:%d, %g Hz, plant %s\n", host.c_str(),
                                actual, options.rate_hz, options.plant.string().c_str()));
  static_cast<void>(std::fflush(stdout));

  std::vector<pollfd> fds{pollfd{listener, POLLIN, 0}};
  std::array<std::uint8_t, MODBUS_TCP_MAX_ADU_LENGTH> query{};
  ServerCounts counts;
  std::int64_t next = runtime::monotonic_ns() + device.period_ns();
  while (g_stop == 0) {
    if (wait_until(fds, next, signals)) {
      if (g_stop != 0) break;
      next = run_due_updates(device, next);
      continue;
    }
    for (std::size_t i = fds.size(); i-- > 0;) {
      if (fds[i].revents == 0) continue;
      if (i == 0) {
        int s = listener;
        const int client = modbus_tcp_pi_accept(ctx.get(), &s);
        if (client >= 0) {
          fds.push_back(pollfd{client, POLLIN, 0});
          ++counts.connections;
        }
        continue;
      }
      modbus_set_socket(ctx.get(), fds[i].fd);
      const int rc = modbus_receive(ctx.get(), query.data());
      if (rc > 0) {
        ++counts.requests;
        if (modbus_reply(ctx.get(), query.data(), rc, device.mapping()) < 0) ++counts.errors;
      } else if (rc < 0) {
        // Closed by the client, or garbage: this connection's framing is lost.
        if (errno != ECONNRESET && errno != 0) ++counts.errors;
        close(fds[i].fd);
        fds.erase(fds.begin() + static_cast<std::ptrdiff_t>(i));
      }
    }
    next = run_due_updates(device, next);
  }
  for (std::size_t i = 1; i < fds.size(); ++i)
    close(fds[i].fd);
  modbus_set_socket(ctx.get(), listener);
  finish(device, counts);
  return 0;
}

int serve_modbus_rtu(const ModbusSimDeviceOptions& options, const std::string& device_path) {
  const StopSignals signals;
  Device device(options, mb::served_register_map());
  set_priority(options.priority);
  const std::unique_ptr<modbus_t, ContextDeleter> ctx(
      modbus_new_rtu(device_path.c_str(), options.baud, 'N', 8, 1));
  if (!ctx) throw std::runtime_error("--modbus-rtu: " + std::string(modbus_strerror(errno)));
  modbus_set_slave(ctx.get(), options.unit_id);
  modbus_set_byte_timeout(ctx.get(), 0, 10'000);
  if (modbus_connect(ctx.get()) != 0) {
    throw std::runtime_error("--modbus-rtu " + device_path + ": " + modbus_strerror(errno));
  }
  static_cast<void>(std::printf("sim-device: modbus-rtu on %s, unit %d, %d baud, %g Hz, plant %s\n",
                                device_path.c_str(), options.unit_id, options.baud, options.rate_hz,
                                options.plant.string().c_str()));
  static_cast<void>(std::fflush(stdout));
  std::vector<pollfd> fds{pollfd{modbus_get_socket(ctx.get()), POLLIN, 0}};
  std::array<std::uint8_t, MODBUS_RTU_MAX_ADU_LENGTH> query{};
  ServerCounts counts;
  std::int64_t next = runtime::monotonic_ns() + device.period_ns();
  while (g_stop == 0) {
    if (!wait_until(fds, next, signals)) {
      const int rc = modbus_receive(ctx.get(), query.data());
      if (rc > 0) {
        ++counts.requests;
        if (modbus_reply(ctx.get(), query.data(), rc, device.mapping()) < 0) ++counts.errors;
      } else if (rc < 0) {
        ++counts.errors;  // CRC or framing error: drop what is left of the frame
        modbus_flush(ctx.get());
      }
    }
    if (g_stop == 0) next = run_due_updates(device, next);
  }
  finish(device, counts);
  return 0;
}

}  // namespace selfsense::drivers::modbus_sim
