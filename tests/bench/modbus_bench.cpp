// Modbus TCP over loopback: how fast the loop can run on the bus, and how long a command takes
// from its sample to the device inside one cycle. A plain program, not a Google Benchmark: the
// figures are wall-clock behaviour of two threads and a server process (rates, deadlines,
// latency distributions), not the CPU time of a function.
//
//   build/tests/bench/modbus_bench [SECONDS_PER_RUN]      (docs/drivers/modbus.md)
//
// `selfsense sim-device --modbus-tcp 127.0.0.1:0` serves the daemon's simulated bench at 20 kHz.
// Runs:
//   as fast as possible: the bus thread polls back to back (poll_rate_hz 1e5, never on time);
//     the loop thread spins on read() and writes a command as soon as a new sample arrives.
//     The poll rate reached is the highest loop rate the bus carries.
//   paced at 1, 2, 5, 10 kHz: the bus thread and a loop thread (clock_nanosleep to absolute
//     deadlines) at the same rate, strict staleness (max_age_s 1.5 periods).
// Per run: polls/s; the read transaction's time; the read-to-write latency (sample published
// by the bus thread -> the command computed from it written on the bus, in the same poll), its
// share of the commands; the loop's statuses.
#include <pthread.h>
#include <sched.h>
#include <sys/prctl.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <map>
#include <memory>
#include <string>
#include <thread>

#include "drivers/modbus/sim_device_process.hpp"
#include "selfsense/drivers/modbus/modbus_driver.hpp"

namespace {

using selfsense::drivers::modbus::ModbusConfig;
using selfsense::drivers::modbus::ModbusDriver;
using selfsense::drivers::modbus::Transport;
using selfsense::runtime::DriverStatus;

std::int64_t now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

double us(std::int64_t ns) {
  return 1e-3 * static_cast<double>(ns);
}

void run(int port, double rate_hz, double seconds) {
  ModbusConfig c;
  c.transport = Transport::kTcp;
  c.port = port;
  c.response_timeout_s = 0.05;
  c.poll_rate_hz = rate_hz > 0.0 ? rate_hz : 100000.0;
  c.max_age_s = rate_hz > 0.0 ? 1.5 / rate_hz : 1e-4;
  c.priority = 60;  // SCHED_FIFO where allowed, as the daemon's bus thread would run
  c.sample_timeout_s = 0.05;
  ModbusDriver d(c);
  std::string why;
  if (!d.configure({rate_hz > 0.0 ? 1.0 / rate_hz : 1e-4}, &why) || !d.activate(&why)) {
    static_cast<void>(std::fprintf(stderr, "modbus_bench: %s\n", why.c_str()));
    std::exit(1);
  }
  while (!d.connected())
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  const selfsense::drivers::modbus::BusStats before = d.bus_stats();
  std::map<DriverStatus, long> statuses;
  const std::int64_t start = now_ns();
  const auto end = start + static_cast<std::int64_t>(seconds * 1e9);
  std::int64_t last_stamp = 0;
  long cycles = 0;
  if (rate_hz > 0.0) {
    const auto period = static_cast<std::int64_t>(std::llround(1e9 / rate_hz));
    for (std::int64_t next = start; next < end; next += period) {
      const timespec ts{static_cast<time_t>(next / 1'000'000'000),
                        static_cast<long>(next % 1'000'000'000)};
      clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
      selfsense::runtime::InputSample in;
      ++statuses[d.read(in)];
      static_cast<void>(d.write({std::isfinite(in.e) ? 0.5 * in.e + 2.5e5 : 0.0}));
      ++cycles;
    }
  } else {
    while (now_ns() < end) {
      selfsense::runtime::InputSample in;
      const DriverStatus s = d.read(in);
      if (in.timestamp_ns == last_stamp) {  // no new sample yet
        const timespec pause{0, 5'000};
        clock_nanosleep(CLOCK_MONOTONIC, 0, &pause, nullptr);
        continue;
      }
      last_stamp = in.timestamp_ns;
      ++statuses[s];
      static_cast<void>(d.write({0.5 * in.e + 2.5e5}));
      ++cycles;
    }
  }
  const double elapsed = 1e-9 * static_cast<double>(now_ns() - start);
  const selfsense::drivers::modbus::BusStats after = d.bus_stats();
  d.deactivate();
  const auto polls = static_cast<double>(after.polls - before.polls);
  const auto latencies = static_cast<double>(after.latencies - before.latencies);
  const auto late = static_cast<double>(after.late_commands - before.late_commands);
  const auto& lat = d.latency_histogram();
  const auto& poll = d.poll_histogram();
  std::printf(
      "%-9s | %8.0f polls/s | read %6.1f us mean, p99 <= %6.1f, max %7.1f | read-to-write "
      "%6.1f us mean, p50 <= %6.1f, p99 <= %7.1f, max %7.1f, %5.1f %% in the same poll | "
      "cycles %ld: ok %ld, stale %ld, timeout %ld, missed deadlines %llu\n",
      rate_hz > 0.0 ? (std::to_string(static_cast<int>(rate_hz)) + " Hz").c_str() : "max",
      polls / elapsed,
      us(static_cast<std::int64_t>(after.poll_ns_sum - before.poll_ns_sum)) / std::max(1.0, polls),
      us(poll.percentile_ns(0.99)), us(poll.max_ns()),
      us(static_cast<std::int64_t>(after.latency_ns_sum - before.latency_ns_sum)) /
          std::max(1.0, latencies),
      us(lat.percentile_ns(0.5)), us(lat.percentile_ns(0.99)), us(lat.max_ns()),
      100.0 * latencies / std::max(1.0, latencies + late), cycles, statuses[DriverStatus::kOk],
      statuses[DriverStatus::kStale], statuses[DriverStatus::kTimeout],
      static_cast<unsigned long long>(after.missed_deadlines - before.missed_deadlines));
}

}  // namespace

int main(int argc, char** argv) {
  const double seconds = argc > 1 ? std::atof(argv[1]) : 2.0;
  // The loop thread at SCHED_FIFO 70 where allowed (the daemon's loop runs at 80 by default).
  sched_param param{};
  param.sched_priority = 70;
  const bool realtime = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param) == 0;
  static_cast<void>(prctl(PR_SET_TIMERSLACK, 1000UL, 0UL, 0UL, 0UL));
  const selfsense::test::SimDeviceProcess device(
      SELFSENSE_CLI, std::string(SELFSENSE_SOURCE_DIR) + "/config/plant/daemon.yaml", 20000.0,
      {"--modbus-tcp", "127.0.0.1:0", "--priority", "50"});
  std::printf(
      "modbus_bench: Modbus TCP on loopback to sim-device (20 kHz) on port %d, %g s per run, "
      "%s\n",
      device.port(), seconds,
      realtime ? "SCHED_FIFO (loop 70, bus 60, device 50)" : "normal scheduling (no rights)");
  run(device.port(), 0.0, seconds);
  for (const double rate : {1000.0, 2000.0, 5000.0, 10000.0})
    run(device.port(), rate, seconds);
  return 0;
}
