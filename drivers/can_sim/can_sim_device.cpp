// The simulated transducer as a CAN node: receives the command frame, steps the plant in real
// time with the command held between frames (zero-order hold, like a DAC) and sends the input
// frames (E, D and, when the layout has them, the reference S and T and the stack's temperature:
// 25 degC plus the plant's self-heating) every period, encoded with
// the layout of the daemon's own configuration (include/selfsense/drivers/can/can_codec.hpp), so
// both ends agree by construction.
//
// One thread: sleep to the next period (absolute deadline on CLOCK_MONOTONIC), drain the
// received command frames, step the plant, send. Round trip: from sending an input frame to the
// kernel's receive time (SIOCGSTAMPNS) of the first command frame after it.
#include "selfsense/drivers/can_sim/can_sim_device.hpp"

#include <linux/can.h>
#include <linux/sockios.h>
#include <sys/ioctl.h>
#include <sys/socket.h>

#include <array>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <ctime>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "node_socket.hpp"
#include "selfsense/drivers/can/can_codec.hpp"
#include "selfsense/plant/plant.hpp"
#include "selfsense/runtime/latency_histogram.hpp"
#include "selfsense/runtime/monotonic.hpp"

namespace selfsense::drivers::can_sim {
namespace {

volatile std::sig_atomic_t g_stop =
    0;  // NOLINT(cppcoreguidelines-avoid-non-const-global-variables)

extern "C" void on_stop_signal(int /*signal*/) {
  g_stop = 1;
}

void install_stop_handlers() {
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  g_stop = 0;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

std::int64_t real_ns() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

int fail(const std::string& message) {
  static_cast<void>(std::fprintf(stderr, "sim-device: %s\n", message.c_str()));
  return 1;
}

// Plant steps per device period, or the reason the rate does not fit the plant.
std::optional<int> plant_substeps(const CanSimDeviceOptions& options, std::string* why) {
  if (!options.plant.is_valid(why)) {
    *why = "--plant: " + *why;
    return std::nullopt;
  }
  if (!(options.rate_hz >= 1.0 && options.rate_hz <= 100000.0)) {
    *why = "--rate: must be within [1, 100000] Hz";
    return std::nullopt;
  }
  const double ratio = options.plant.sample_rate_hz / options.rate_hz;
  const double substeps = std::round(ratio);
  if (substeps < 1.0 || std::abs(ratio - substeps) > 1e-9 * ratio) {
    *why = "--rate: " + std::to_string(options.rate_hz) +
           " Hz must divide the plant's sample_rate_hz " +
           std::to_string(options.plant.sample_rate_hz);
    return std::nullopt;
  }
  return static_cast<int>(substeps);
}

// One input frame to send and the signals it carries.
struct OutFrame {
  canfd_frame frame{};
  std::vector<std::pair<const can::SignalConfig*, int>> signals{};  // signal, channel 0..4
};

// The input frames of the layout, each with the signals it carries (pointers into layout).
std::vector<OutFrame> input_frames(const can::CanConfig& layout) {
  std::vector<OutFrame> frames;
  const std::array<const can::SignalConfig*, 5> channels{&layout.e, &layout.d, &layout.s_ref,
                                                         &layout.t_ref, &layout.temp};
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
  return frames;
}

struct NodeCounts {
  std::uint64_t ticks{0};
  std::uint64_t late{0};
  std::uint64_t sent{0};
  std::uint64_t send_drops{0};
  std::uint64_t commands{0};
  std::uint64_t bad_commands{0};
  std::uint64_t command_timeouts{0};
};

// The node between set-up and stop: one tick() per device period.
class CanNode final {
 public:
  CanNode(const CanSimDeviceOptions& options, int fd, int substeps)
      : layout_(&options.layout),
        fd_(fd),
        substeps_(substeps),
        frames_(input_frames(options.layout)),
        mtu_(options.layout.fd ? CANFD_MTU : CAN_MTU),
        command_bytes_(can::bytes_needed(options.layout.command.signal)),
        timeout_ns_(static_cast<std::int64_t>(std::llround(options.command_timeout_ms * 1e6))),
        plant_(options.plant) {}

  void tick(std::int64_t now) {
    ++counts_.ticks;
    drain_commands(now);
    expire_command(now);
    send_inputs(step_plant());
  }
  void count_late() noexcept { ++counts_.late; }
  void print_summary() const;

 private:
  // Takes every command frame received since the last tick; the last one holds.
  void drain_commands(std::int64_t now);
  // No command for the timeout: E = 0 until the next one.
  void expire_command(std::int64_t now) noexcept {
    if (!timed_out_ && now - last_command_ns_ > timeout_ns_) {
      timed_out_ = true;
      ++counts_.command_timeouts;
    }
  }
  // One device period of the plant with the command held: E, D, S, T, temperature.
  std::array<double, 5> step_plant() {
    const plant::StepInput input{timed_out_ ? 0.0 : command_, 0.0, 25.0};
    plant::StepOutput o{};
    for (int i = 0; i < substeps_; ++i)
      o = plant_.step(input);
    return {o.e_meas_v_per_m, o.d_meas_c_per_m2, o.s, o.t_pa, o.temp_degc};
  }
  void send_inputs(const std::array<double, 5>& values);

  const can::CanConfig* layout_;
  int fd_;
  int substeps_;
  std::vector<OutFrame> frames_;
  std::size_t mtu_;
  std::size_t command_bytes_;
  std::int64_t timeout_ns_;
  plant::Plant plant_;
  double command_{0.0};
  std::int64_t last_command_ns_{0};
  bool timed_out_{true};
  std::int64_t sent_real_ns_{0};  // CLOCK_REALTIME, the clock of the kernel's rx stamps
  bool awaiting_{false};
  NodeCounts counts_{};
  runtime::LatencyHistogram round_trip_{};
};

void CanNode::drain_commands(std::int64_t now) {
  canfd_frame rx{};
  for (;;) {
    const ssize_t n = ::recv(fd_, &rx, sizeof(rx), MSG_DONTWAIT);
    if (n < 0) break;
    if ((n != static_cast<ssize_t>(CAN_MTU) && n != static_cast<ssize_t>(CANFD_MTU)) ||
        rx.len < command_bytes_) {
      ++counts_.bad_commands;
      continue;
    }
    command_ = can::decode(std::span<const std::uint8_t>(rx.data, rx.len), layout_->command.signal);
    ++counts_.commands;
    last_command_ns_ = now;
    timed_out_ = false;
    if (awaiting_) {
      timespec stamp{};
      const std::int64_t rx_ns =
          ::ioctl(fd_, SIOCGSTAMPNS, &stamp) == 0
              ? static_cast<std::int64_t>(stamp.tv_sec) * 1'000'000'000 + stamp.tv_nsec
              : real_ns();
      round_trip_.record(rx_ns - sent_real_ns_);
      awaiting_ = false;
    }
  }
}

void CanNode::send_inputs(const std::array<double, 5>& values) {
  for (OutFrame& f : frames_) {
    const std::span<std::uint8_t> data(f.frame.data, f.frame.len);
    for (const auto& [signal, channel] : f.signals) {
      static_cast<void>(
          can::encode(data, signal->signal, values.at(static_cast<std::size_t>(channel))));
    }
    if (::send(fd_, &f.frame, mtu_, MSG_DONTWAIT) == static_cast<ssize_t>(mtu_)) {
      ++counts_.sent;
    } else {
      ++counts_.send_drops;
    }
  }
  sent_real_ns_ = real_ns();
  awaiting_ = true;
}

void CanNode::print_summary() const {
  std::printf(
      "sim-device: stopped: ticks=%llu late=%llu frames_sent=%llu send_drops=%llu "
      "commands=%llu bad_commands=%llu command_timeouts=%llu round_trip_us p50=%.0f p99=%.0f "
      "max=%.0f (n=%lld)\n",
      static_cast<unsigned long long>(counts_.ticks), static_cast<unsigned long long>(counts_.late),
      static_cast<unsigned long long>(counts_.sent),
      static_cast<unsigned long long>(counts_.send_drops),
      static_cast<unsigned long long>(counts_.commands),
      static_cast<unsigned long long>(counts_.bad_commands),
      static_cast<unsigned long long>(counts_.command_timeouts),
      static_cast<double>(round_trip_.percentile_ns(0.5)) / 1e3,
      static_cast<double>(round_trip_.percentile_ns(0.99)) / 1e3,
      static_cast<double>(round_trip_.max_ns()) / 1e3, static_cast<long long>(round_trip_.count()));
}

// Ticks the node every period until a stop signal or the end; a tick more than a period late
// is counted, and more than ten periods behind the schedule starts again from now.
void run_paced(CanNode& node, double rate_hz, double duration_s) {
  const auto period_ns = static_cast<std::int64_t>(std::llround(1e9 / rate_hz));
  const std::int64_t start = runtime::monotonic_ns();
  const std::int64_t end =
      duration_s > 0.0 ? start + static_cast<std::int64_t>(duration_s * 1e9) : 0;
  std::int64_t next = start + period_ns;
  while (g_stop == 0) {
    // A signal ends the sleep early: look at the stop flag before the next tick.
    if (runtime::sleep_once_until(next) != runtime::Wake::kDeadline) continue;
    const std::int64_t now = runtime::monotonic_ns();
    if (end != 0 && now >= end) break;
    if (now - next > period_ns) {
      node.count_late();
      if (now - next > 10 * period_ns) next = now;
    }
    next += period_ns;
    node.tick(now);
  }
}

}  // namespace

int run_can_sim_device(const CanSimDeviceOptions& options) {
  std::string why;
  const std::optional<int> substeps = plant_substeps(options, &why);
  if (!substeps) return fail(why);
  NodeSocket socket;
  if (!socket.open(options.layout, &why)) return fail(why);
  CanNode node(options, socket.fd(), *substeps);
  install_stop_handlers();
  std::printf("sim-device: CAN node on %s (%s), %g Hz, plant at %g Hz\n",
              options.layout.interface.c_str(), options.layout.fd ? "CAN FD" : "classic CAN",
              options.rate_hz, options.plant.sample_rate_hz);
  static_cast<void>(std::fflush(stdout));
  run_paced(node, options.rate_hz, options.duration_s);
  node.print_summary();
  return 0;
}

}  // namespace selfsense::drivers::can_sim
