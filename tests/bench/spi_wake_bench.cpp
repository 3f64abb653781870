// The loop's wake-up latency when the ADC's data-ready edge paces it (pace drdy): from the
// edge's time stamp to the moment LoopRunner's thread runs again after its wait, the figure the
// daemon's status shows as timing.wake_latency_ns in that mode. A plain program printing
// figures, like spi_bench.
//
//   build/tests/bench/spi_wake_bench [SECONDS] [PRIORITY]     (docs/drivers/spi.md; 10 s, 0)
//
// PRIORITY 0 runs both threads under the normal scheduler; 1..98 runs the loop under
// SCHED_FIFO at PRIORITY and the edge thread at PRIORITY + 1 (needs CAP_SYS_NICE).
//
// What is real and what is emulated. The loop (LoopRunner, Loop, the SPI driver, the shipped
// hysteresis-creep model, position control) runs in real time on CLOCK_MONOTONIC, waiting in
// the kernel at the driver's GpioLine seam exactly as on the board: one blocking poll per cycle.
// The data-ready line behind the seam is a thread that "fires" every 50 us (20 kHz, absolute
// deadlines): it stamps the edge with CLOCK_MONOTONIC and wakes the loop through an eventfd,
// as the GPIO character device stamps an edge in its interrupt handler and wakes the poll. The
// latency measured is thus the kernel's cross-thread wake-up of the loop plus the driver's wait
// code; on a board the interrupt's own latency (edge to stamp) comes before it and is not in
// the figure. The ADC and DAC behind the SpiBus seam are the chip emulators of
// tests/support/spi in simulated time; each emulated conversion (which steps the simulated
// transducer) is run before the wait for the edge that announces it, so that its cost, which the
// silicon spends while the CPU sleeps, is not in the wake-up figure.
#include <poll.h>
#include <pthread.h>
#include <sched.h>
#include <sys/eventfd.h>
#include <sys/prctl.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "selfsense/model_io/model_yaml.hpp"
#include "selfsense/models/runtime_model.hpp"
#include "selfsense/runtime/loop.hpp"
#include "selfsense/runtime/loop_runner.hpp"
#include "support/daemon_plant.hpp"
#include "support/spi/spi_bench.hpp"

namespace {

using namespace selfsense;  // NOLINT(google-build-using-namespace): a short program

std::int64_t now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

// The data-ready line: edges fired by a thread in real time, taken at the GpioLine seam by the
// loop's thread (one blocking ppoll on an eventfd when none is queued). Before each wait for an
// edge, one conversion of the emulated ADC is run (in its simulated time), the one that edge
// announces.
class RealTimeDrdy final : public drivers::spi::GpioLine {
 public:
  explicit RealTimeDrdy(drivers::spi::GpioLine& emulated)
      : emulated_(&emulated), fd_(eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC)) {}
  ~RealTimeDrdy() override {
    if (fd_ >= 0) ::close(fd_);
  }
  RealTimeDrdy(const RealTimeDrdy&) = delete;
  RealTimeDrdy& operator=(const RealTimeDrdy&) = delete;
  RealTimeDrdy(RealTimeDrdy&&) = delete;
  RealTimeDrdy& operator=(RealTimeDrdy&&) = delete;

  [[nodiscard]] bool ok() const noexcept { return fd_ >= 0; }
  int read() noexcept override { return emulated_->read(); }
  bool write(bool /*high*/) noexcept override { return false; }

  drivers::spi::EdgeWait wait_edge(std::int64_t timeout_ns,
                                   drivers::spi::Edge* edge) noexcept override {
    if (!converted_) {
      // The emulated conversion due at the next edge (advances the emulator's simulated clock).
      if (emulated_->wait_edge(1'000'000'000, nullptr) != drivers::spi::EdgeWait::kEdge) {
        return drivers::spi::EdgeWait::kError;
      }
      converted_ = true;
    }
    const std::int64_t deadline = now_ns() + timeout_ns;
    while (taken_ == fired_.load(std::memory_order_acquire)) {
      const std::int64_t left = deadline - now_ns();
      if (left <= 0) return drivers::spi::EdgeWait::kTimeout;
      pollfd p{fd_, POLLIN, 0};
      const timespec t{static_cast<time_t>(left / 1'000'000'000),
                       static_cast<long>(left % 1'000'000'000)};
      const int rc = ::ppoll(&p, 1, &t, nullptr);
      if (rc < 0) return drivers::spi::EdgeWait::kError;
      std::uint64_t n = 0;
      static_cast<void>(::read(fd_, &n, sizeof(n)));  // clears the count; edges are in the ring
    }
    const std::uint64_t i = taken_++ % kRing;
    const std::int64_t stamp = stamps_[i].load(std::memory_order_relaxed);
    // Exact figures beside the status' power-of-two buckets: the wake-up as the seam sees it
    // (the first edge of each wait; queued ones taken at once would repeat the lateness).
    if (timeout_ns > 0 && woken_.size() < woken_.capacity()) woken_.push_back(now_ns() - stamp);
    if (edge != nullptr) *edge = {false, stamp};
    converted_ = false;
    return drivers::spi::EdgeWait::kEdge;
  }

  // The edge thread's side.
  void fire() noexcept {
    const std::uint64_t n = fired_.load(std::memory_order_relaxed);
    stamps_[n % kRing].store(now_ns(), std::memory_order_relaxed);
    fired_.store(n + 1, std::memory_order_release);
    const std::uint64_t one = 1;
    static_cast<void>(::write(fd_, &one, sizeof(one)));
  }
  [[nodiscard]] std::uint64_t fired() const noexcept {
    return fired_.load(std::memory_order_relaxed);
  }
  // Room for n wake-up figures, reserved before the loop runs (no allocation in it).
  void reserve(std::size_t n) { woken_.reserve(n); }
  [[nodiscard]] std::vector<std::int64_t>& woken() noexcept { return woken_; }

 private:
  static constexpr std::uint64_t kRing = 4096;  // 0.2 s of edges at 20 kHz
  drivers::spi::GpioLine* emulated_;
  int fd_;
  std::array<std::atomic<std::int64_t>, kRing> stamps_{};
  std::atomic<std::uint64_t> fired_{0};
  std::uint64_t taken_{0};             // loop thread only
  bool converted_{false};              // loop thread only
  std::vector<std::int64_t> woken_{};  // loop thread only until it stops
};

double pct_us(std::vector<std::int64_t>& v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const auto i = static_cast<std::size_t>(
      std::min<double>(q * static_cast<double>(v.size()), static_cast<double>(v.size() - 1)));
  return 1e-3 * static_cast<double>(v[i]);
}

bool set_fifo(int priority) {
  if (priority <= 0) return true;
  sched_param sp{};
  sp.sched_priority = priority;
  return pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp) == 0;
}

double us(std::int64_t ns) {
  return static_cast<double>(ns) * 1e-3;
}

}  // namespace

int main(int argc, char** argv) {
  const double seconds = argc > 1 ? std::strtod(argv[1], nullptr) : 10.0;
  const int priority = argc > 2 ? static_cast<int>(std::strtol(argv[2], nullptr, 10)) : 0;
  constexpr double kRate = 20000.0;
  constexpr double kTs = 1.0 / kRate;
  constexpr std::int64_t kPeriodNs = 50'000;
  const models::TransducerModel model =
      models::load_model(std::string(SELFSENSE_SOURCE_DIR) + "/config/models/sim.yaml");
  test::SpiBench bench(test::emulated_spi_config(kRate), test::daemon_plant(kRate));
  RealTimeDrdy drdy(bench.adc.drdy_line());
  if (!drdy.ok()) {
    std::perror("spi_wake_bench: eventfd");
    return 1;
  }
  drdy.reserve(static_cast<std::size_t>((seconds + 1.0) * kRate * 1.2));
  runtime::SteadyClock steady;
  drivers::spi::SpiDriver driver(
      bench.config, {&bench.adc, &bench.dac, &drdy, &bench.enable, &bench.fault, &steady}, false);
  std::string why;
  if (!driver.configure({kTs}, &why) || !driver.activate(&why)) {
    static_cast<void>(std::fprintf(stderr, "spi_wake_bench: %s\n", why.c_str()));
    return 1;
  }
  runtime::ControllerConfig control;
  control.position.gains = {2e8, 2.5e11, 0.0};
  control.position.tracking_time = 1e-3;
  control.position_shaper.slew_rate = 0.05;
  control.command_min = 0.0;
  control.command_max = 2e6;
  runtime::LoopConfig lc;
  lc.sample_time = kTs;
  runtime::Loop loop(lc, driver,
                     std::make_unique<models::Reconstruction>(model, models::RuntimeOptions{kTs}),
                     runtime::Controller(control, model.actuator, kTs), nullptr);

  runtime::LoopRunner runner(loop, steady, kPeriodNs, runtime::RtOptions{priority, -1},
                             driver.cycle_trigger());
  const runtime::RtSetupResult rt = runner.start();
  // The edges start once the loop thread waits for them (none queued through its set-up).
  std::atomic<bool> stop{false};
  bool edge_fifo = true;
  std::thread edges([&] {
    edge_fifo = set_fifo(priority > 0 ? priority + 1 : 0);
    // Deadlines kept to 1 us, not the normal thread's 50 us timer slack (20 kHz is 50 us).
    static_cast<void>(prctl(PR_SET_TIMERSLACK, 1000UL, 0UL, 0UL, 0UL));
    std::int64_t next = now_ns() + kPeriodNs;
    while (!stop.load(std::memory_order_relaxed)) {
      const timespec t{static_cast<time_t>(next / 1'000'000'000),
                       static_cast<long>(next % 1'000'000'000)};
      while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &t, nullptr) == EINTR) {
      }
      drdy.fire();
      next += kPeriodNs;
      const std::int64_t now = now_ns();
      if (now > next) next += (now - next) / kPeriodNs * kPeriodNs + kPeriodNs;  // skip, late
    }
  });
  std::uint64_t id = 0;
  const auto send = [&](runtime::LoopCommand c) {
    c.id = ++id;
    static_cast<void>(loop.submit(c));
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  };
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  send({0, runtime::CommandKind::kReset});
  send({0, runtime::CommandKind::kMode, 0.0, runtime::ControlMode::kPosition});
  send({0, runtime::CommandKind::kArm});
  send({0, runtime::CommandKind::kSetpoint, 0.4e-3});
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  const runtime::StatusSnapshot s = loop.status();
  runner.stop();
  stop.store(true);
  edges.join();
  driver.deactivate();
  runtime::LoopAnswer answer;
  while (loop.take_answer(answer)) {
  }

  const drivers::spi::SpiCounters spi = driver.spi_counters();
  std::printf("spi_wake_bench: %.0f s at 20 kHz, data-ready paced, loop %s, edge thread %s%s\n",
              seconds, rt.fifo ? ("SCHED_FIFO " + std::to_string(priority)).c_str() : "SCHED_OTHER",
              priority > 0 && edge_fifo ? "SCHED_FIFO +1" : "SCHED_OTHER",
              rt.memory_locked ? ", memory locked" : "");
  std::printf(
      "wake-up latency (edge stamp .. loop thread running) us: p50<=%.1f p99<=%.1f max=%.1f "
      "(status timing.wake_latency_ns; histogram bucket bounds)\n",
      us(s.wake_latency_p50_ns), us(s.wake_latency_p99_ns), us(s.wake_latency_max_ns));
  std::vector<std::int64_t>& w = drdy.woken();
  std::printf(
      "wake-up latency at the seam (edge stamp .. poll returned, %zu waits) us: p50=%.1f "
      "p99=%.1f p99.9=%.1f max=%.1f\n",
      w.size(), pct_us(w, 0.5), pct_us(w, 0.99), pct_us(w, 0.999), pct_us(w, 1.0));
  std::printf("cycle time us: p50<=%.1f p99<=%.1f max=%.1f\n", us(s.cycle_time_p50_ns),
              us(s.cycle_time_p99_ns), us(s.cycle_time_max_ns));
  std::printf(
      "cycles %lld, edges fired %llu, late cycles (no edge within 2 periods) %lld, edges missed "
      "(loop too late, skipped) %llu, state at the end: %s\n",
      static_cast<long long>(s.cycle), static_cast<unsigned long long>(drdy.fired()),
      static_cast<long long>(s.overruns), static_cast<unsigned long long>(spi.drdy_missed),
      runtime::to_string(s.state));
  std::string faults;
  for (std::size_t i = 0; i < runtime::kFaultCount; ++i) {
    const auto f = static_cast<runtime::Fault>(i);
    if (s.fault_records[i].count > 0 && f != runtime::Fault::kPowerUp) {
      faults +=
          " " + std::string(runtime::to_string(f)) + "=" + std::to_string(s.fault_records[i].count);
    }
  }
  std::printf("faults seen (cycles):%s\n", faults.empty() ? " none" : faults.c_str());
  return 0;
}
