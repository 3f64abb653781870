// The simulated transducer as a CAN node: receives the command frame, steps the plant in real
// time with the command held between frames (zero-order hold, like a DAC) and sends the input
// frames (E, D and, when the layout has them, the reference S and T) every period, encoded with
// the layout of the daemon's own configuration (include/selfsense/drivers/can/can_codec.hpp), so
// both ends agree by construction.
//
// One thread: sleep to the next period (absolute deadline on CLOCK_MONOTONIC), drain the
// received command frames, step the plant, send. Round trip: from sending an input frame to the
// kernel's receive time (SIOCGSTAMPNS) of the first command frame after it.
#include "sim_device_can.hpp"

#include <linux/can.h>
#include <linux/can/raw.h>
#include <linux/sockios.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <exception>
#include <memory>
#include <span>
#include <vector>

#include "selfsense/daemon/config.hpp"
#include "selfsense/drivers/can/can_codec.hpp"
#include "selfsense/drivers/can/can_config.hpp"
#include "selfsense/drivers/registry/registry.hpp"
#include "selfsense/plant/plant.hpp"
#include "selfsense/plant_io/plant_yaml.hpp"
#include "selfsense/runtime/latency_histogram.hpp"

namespace selfsense::cli {
namespace {

namespace can = drivers::can;

volatile std::sig_atomic_t g_stop =
    0;  // NOLINT(cppcoreguidelines-avoid-non-const-global-variables)

extern "C" void on_stop_signal(int /*signal*/) {
  g_stop = 1;
}

std::int64_t mono_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

std::int64_t real_ns() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

canid_t wire_id(const can::FrameId& f) {
  return f.extended ? (f.id & CAN_EFF_MASK) | CAN_EFF_FLAG : f.id & CAN_SFF_MASK;
}

// Closes the socket on every way out.
struct Socket {
  int fd{-1};
  Socket() = default;
  Socket(const Socket&) = delete;
  Socket& operator=(const Socket&) = delete;
  Socket(Socket&&) = delete;
  Socket& operator=(Socket&&) = delete;
  ~Socket() {
    if (fd >= 0) ::close(fd);
  }
};

int fail(const std::string& message) {
  static_cast<void>(std::fprintf(stderr, "sim-device: %s\n", message.c_str()));
  return 1;
}

// One input frame to send and the signals it carries.
struct OutFrame {
  canfd_frame frame{};
  std::vector<std::pair<const can::SignalConfig*, int>> signals{};  // signal, channel 0..3
};

}  // namespace

int run_can_sim_device(const CanSimDeviceOptions& options) {
  drivers::Registry registry;
  const daemon::ConfigResult loaded = daemon::load_config(options.config, &registry);
  if (!loaded.ok()) {
    for (const std::string& p : loaded.problems)
      static_cast<void>(std::fprintf(stderr, "%s\n", p.c_str()));
    return fail(options.config.string() + ": not a valid daemon configuration");
  }
  if (loaded.config.driver_type != "can") {
    return fail(options.config.string() + ": driver.type is '" + loaded.config.driver_type +
                "', not can (the CAN node takes its frame layout from a can driver section)");
  }
  can::CanConfig layout = registry.can_config();
  if (!options.interface.empty()) layout.interface = options.interface;

  plant::PlantConfig plant_config;
  try {
    if (!options.plant.empty()) plant_config = plant::load_plant_file(options.plant).plant;
  } catch (const std::exception& e) {
    return fail(std::string("--plant: ") + e.what());
  }
  std::string why;
  if (!plant_config.is_valid(&why)) return fail("--plant: " + why);
  if (!(options.rate_hz >= 1.0 && options.rate_hz <= 100000.0)) {
    return fail("--rate: must be within [1, 100000] Hz");
  }
  const double ratio = plant_config.sample_rate_hz / options.rate_hz;
  const double substeps_d = std::round(ratio);
  if (substeps_d < 1.0 || std::abs(ratio - substeps_d) > 1e-9 * ratio) {
    return fail("--rate: " + std::to_string(options.rate_hz) +
                " Hz must divide the plant's sample_rate_hz " +
                std::to_string(plant_config.sample_rate_hz));
  }
  const int substeps = static_cast<int>(substeps_d);

  Socket sock;
  sock.fd = ::socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (sock.fd < 0) {
    return fail(std::string("socket(PF_CAN): ") + std::strerror(errno) +
                " (a kernel without SocketCAN? modprobe can can_raw)");
  }
  ifreq ifr{};
  static_cast<void>(
      std::snprintf(ifr.ifr_name, sizeof(ifr.ifr_name), "%s", layout.interface.c_str()));
  if (::ioctl(sock.fd, SIOCGIFINDEX, &ifr) < 0) {
    return fail("--can " + layout.interface + ": " + std::strerror(errno));
  }
  const int index = ifr.ifr_ifindex;
  if (layout.fd) {
    const int on = 1;
    if (::ioctl(sock.fd, SIOCGIFMTU, &ifr) < 0 || ifr.ifr_mtu != static_cast<int>(CANFD_MTU) ||
        ::setsockopt(sock.fd, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof(on)) < 0) {
      return fail("--can " + layout.interface + ": CAN FD (driver.fd) needs MTU 72");
    }
  }
  const can::FrameId command_id = layout.command.frame;
  can_filter filter{wire_id(command_id), (command_id.extended ? CAN_EFF_MASK : CAN_SFF_MASK) |
                                             CAN_EFF_FLAG | CAN_RTR_FLAG};
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = index;
  if (::setsockopt(sock.fd, SOL_CAN_RAW, CAN_RAW_FILTER, &filter, sizeof(filter)) < 0 ||
      ::bind(sock.fd, reinterpret_cast<const sockaddr*>(&addr), sizeof(addr)) < 0) {
    return fail("--can " + layout.interface + ": bind: " + std::strerror(errno));
  }

  // The input frames, each with the signals it carries.
  std::vector<OutFrame> frames;
  const std::array<const can::SignalConfig*, 4> channels{&layout.e, &layout.d, &layout.s_ref,
                                                         &layout.t_ref};
  for (const can::FrameLayout& f : layout.input_frames()) {
    OutFrame out;
    out.frame.can_id = wire_id(f.id);
    out.frame.len = static_cast<std::uint8_t>(layout.frame_length(f.bytes));
    if (layout.fd) out.frame.flags = CANFD_BRS;
    for (std::size_t c = 0; c < channels.size(); ++c) {
      if (channels.at(c)->present && channels.at(c)->frame == f.id) {
        out.signals.emplace_back(channels.at(c), static_cast<int>(c));
      }
    }
    frames.push_back(out);
  }
  const std::size_t mtu = layout.fd ? CANFD_MTU : CAN_MTU;
  const std::size_t command_bytes = can::bytes_needed(layout.command.signal);

  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  g_stop = 0;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);

  plant::Plant plant(plant_config);
  const auto period_ns = static_cast<std::int64_t>(std::llround(1e9 / options.rate_hz));
  const auto timeout_ns = static_cast<std::int64_t>(std::llround(options.command_timeout_ms * 1e6));
  const std::int64_t start = mono_ns();
  const std::int64_t end =
      options.duration_s > 0.0 ? start + static_cast<std::int64_t>(options.duration_s * 1e9) : 0;
  std::int64_t next = start + period_ns;
  double command = 0.0;
  std::int64_t last_command_ns = 0;
  bool timed_out = true;
  std::int64_t sent_real_ns = 0;  // CLOCK_REALTIME, the clock of the kernel's rx stamps
  bool awaiting = false;
  std::uint64_t ticks = 0;
  std::uint64_t late = 0;
  std::uint64_t sent = 0;
  std::uint64_t send_drops = 0;
  std::uint64_t commands = 0;
  std::uint64_t bad_commands = 0;
  std::uint64_t command_timeouts = 0;
  runtime::LatencyHistogram round_trip;
  std::printf("sim-device: CAN node on %s (%s), %g Hz, plant at %g Hz\n", layout.interface.c_str(),
              layout.fd ? "CAN FD" : "classic CAN", options.rate_hz, plant_config.sample_rate_hz);
  static_cast<void>(std::fflush(stdout));

  while (g_stop == 0) {
    timespec deadline{static_cast<time_t>(next / 1'000'000'000),
                      static_cast<long>(next % 1'000'000'000)};
    if (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &deadline, nullptr) != 0) continue;
    const std::int64_t now = mono_ns();
    if (end != 0 && now >= end) break;
    if (now - next > period_ns) {
      ++late;
      if (now - next > 10 * period_ns) next = now;  // far behind: start again from now
    }
    next += period_ns;
    ++ticks;

    canfd_frame rx{};
    for (;;) {
      const ssize_t n = ::recv(sock.fd, &rx, sizeof(rx), MSG_DONTWAIT);
      if (n < 0) break;
      if ((n != static_cast<ssize_t>(CAN_MTU) && n != static_cast<ssize_t>(CANFD_MTU)) ||
          rx.len < command_bytes) {
        ++bad_commands;
        continue;
      }
      command = can::decode(std::span<const std::uint8_t>(rx.data, rx.len), layout.command.signal);
      ++commands;
      last_command_ns = now;
      timed_out = false;
      if (awaiting) {
        timespec stamp{};
        const std::int64_t rx_ns =
            ::ioctl(sock.fd, SIOCGSTAMPNS, &stamp) == 0
                ? static_cast<std::int64_t>(stamp.tv_sec) * 1'000'000'000 + stamp.tv_nsec
                : real_ns();
        round_trip.record(rx_ns - sent_real_ns);
        awaiting = false;
      }
    }
    if (!timed_out && now - last_command_ns > timeout_ns) {
      timed_out = true;
      ++command_timeouts;
    }
    const plant::StepInput input{timed_out ? 0.0 : command, 0.0, 25.0};
    plant::StepOutput o{};
    for (int i = 0; i < substeps; ++i)
      o = plant.step(input);
    const std::array<double, 4> values{o.e_meas_v_per_m, o.d_meas_c_per_m2, o.s, o.t_pa};
    for (OutFrame& f : frames) {
      const std::span<std::uint8_t> data(f.frame.data, f.frame.len);
      for (const auto& [signal, channel] : f.signals) {
        static_cast<void>(
            can::encode(data, signal->signal, values.at(static_cast<std::size_t>(channel))));
      }
      if (::send(sock.fd, &f.frame, mtu, MSG_DONTWAIT) == static_cast<ssize_t>(mtu)) {
        ++sent;
      } else {
        ++send_drops;
      }
    }
    sent_real_ns = real_ns();
    awaiting = true;
  }
  std::printf(
      "sim-device: stopped: ticks=%llu late=%llu frames_sent=%llu send_drops=%llu "
      "commands=%llu bad_commands=%llu command_timeouts=%llu round_trip_us p50=%.0f p99=%.0f "
      "max=%.0f (n=%lld)\n",
      static_cast<unsigned long long>(ticks), static_cast<unsigned long long>(late),
      static_cast<unsigned long long>(sent), static_cast<unsigned long long>(send_drops),
      static_cast<unsigned long long>(commands), static_cast<unsigned long long>(bad_commands),
      static_cast<unsigned long long>(command_timeouts),
      static_cast<double>(round_trip.percentile_ns(0.5)) / 1e3,
      static_cast<double>(round_trip.percentile_ns(0.99)) / 1e3,
      static_cast<double>(round_trip.max_ns()) / 1e3, static_cast<long long>(round_trip.count()));
  return 0;
}

}  // namespace selfsense::cli
