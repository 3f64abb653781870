// The SPI driver on the chip emulators: how long one loop cycle takes from the start of read()
// to the end of write() (the ADC frame transfer and decoding, reconstruction with the shipped
// hysteresis-creep model, control, the DAC frame), and the loop rate that leaves. A plain
// program, not a Google Benchmark, like modbus_bench: the figures are distributions of
// wall-clock times of whole cycles, printed with the settings they were taken at.
//
//   build/tests/bench/spi_bench [CYCLES]          (docs/drivers/spi.md; default 200000)
//
// The loop runs at 20 kHz in simulated time (config/spi-ads131m04.yaml's rate, the model
// config/models/sim.yaml identified at 20 kHz), armed in position mode on a 1 Hz sine, each
// cycle paced by the emulated ADC's data-ready edge. Each conversion steps the simulated
// transducer inside the emulator's data-ready wait, outside the timed span; the times are those
// of the code that runs on the target. What the emulator cannot give: the SPI bit times (18
// bytes at 8 MHz: 18 us; 3 bytes at 10 MHz: 2.4 us) and the kernel's spidev and controller
// overhead per ioctl, which a board adds to these figures (docs/drivers/spi.md).
#include "support/spi/spi_bench.hpp"

#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <numbers>
#include <vector>

#include "selfsense/model_io/model_yaml.hpp"
#include "selfsense/models/runtime_model.hpp"
#include "selfsense/runtime/loop.hpp"
#include "support/daemon_plant.hpp"

namespace {

using namespace selfsense;  // NOLINT(google-build-using-namespace): a short program

std::int64_t now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

double pct_us(std::vector<std::int64_t>& v, double q) {
  std::sort(v.begin(), v.end());
  const auto i = static_cast<std::size_t>(
      std::min<double>(q * static_cast<double>(v.size()), static_cast<double>(v.size() - 1)));
  return 1e-3 * static_cast<double>(v[i]);
}

}  // namespace

int main(int argc, char** argv) {
  const long cycles = argc > 1 ? std::strtol(argv[1], nullptr, 10) : 200000;
  constexpr double kRate = 20000.0;
  constexpr double kTs = 1.0 / kRate;
  const models::TransducerModel model =
      models::load_model(std::string(SELFSENSE_SOURCE_DIR) + "/config/models/sim.yaml");
  test::SpiBench bench(test::emulated_spi_config(kRate), test::daemon_plant(kRate));
  std::string why;
  if (!bench.driver.configure({kTs}, &why) || !bench.driver.activate(&why)) {
    static_cast<void>(std::fprintf(stderr, "spi_bench: %s\n", why.c_str()));
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
  runtime::Loop loop(lc, bench.driver,
                     std::make_unique<models::Reconstruction>(model, models::RuntimeOptions{kTs}),
                     runtime::Controller(control, model.actuator, kTs), nullptr);
  runtime::CycleTrigger* trigger = bench.driver.cycle_trigger();
  std::uint64_t id = 0;
  const auto send = [&](runtime::LoopCommand c) {
    c.id = ++id;
    static_cast<void>(loop.submit(c));
  };
  const auto step = [&] {
    static_cast<void>(trigger->wait(200'000));
    loop.cycle(false);
  };
  for (int k = 0; k < 4000; ++k)
    step();
  send({0, runtime::CommandKind::kReset});
  step();
  send({0, runtime::CommandKind::kMode, 0.0, runtime::ControlMode::kPosition});
  step();
  send({0, runtime::CommandKind::kArm});
  step();

  std::vector<std::int64_t> cycle_ns(static_cast<std::size_t>(cycles));
  std::vector<std::int64_t> read_ns(static_cast<std::size_t>(cycles));
  std::vector<std::int64_t> write_ns(static_cast<std::size_t>(cycles));
  runtime::InputSample in;
  runtime::LoopAnswer answer;
  for (long k = 0; k < cycles; ++k) {
    const double phase = 2.0 * std::numbers::pi * static_cast<double>(k) * kTs;
    if (k % 20 == 0) send({0, runtime::CommandKind::kSetpoint, 0.6e-3 - 0.4e-3 * std::cos(phase)});
    static_cast<void>(trigger->wait(200'000));
    const std::int64_t t0 = now_ns();
    loop.cycle(false);
    cycle_ns[static_cast<std::size_t>(k)] = now_ns() - t0;
    while (loop.take_answer(answer)) {
    }
  }
  const bool armed = loop.supervisor().state() == runtime::LoopState::kArmed;
  // The driver's own share: read() and write() alone, the same frames.
  for (long k = 0; k < cycles; ++k) {
    static_cast<void>(trigger->wait(200'000));
    const std::int64_t t0 = now_ns();
    static_cast<void>(bench.driver.read(in));
    const std::int64_t t1 = now_ns();
    static_cast<void>(bench.driver.write({1e6}));
    const std::int64_t t2 = now_ns();
    read_ns[static_cast<std::size_t>(k)] = t1 - t0;
    write_ns[static_cast<std::size_t>(k)] = t2 - t1;
  }
  const runtime::DriverCounters c = bench.driver.counters();
  const double p50 = pct_us(cycle_ns, 0.5);
  const double p99 = pct_us(cycle_ns, 0.99);
  const double p999 = pct_us(cycle_ns, 0.999);
  const double mx = 1e-3 * static_cast<double>(cycle_ns.back());
  std::printf("spi_bench: %ld cycles at 20 kHz (simulated time), position mode, armed at end: %s\n",
              cycles, armed ? "yes" : "NO");
  std::printf(
      "read-to-write (read() start .. write() end, whole cycle) us: p50=%.2f p99=%.2f "
      "p99.9=%.2f max=%.2f\n",
      p50, p99, p999, mx);
  std::printf("driver read() us: p50=%.2f p99=%.2f; write() us: p50=%.2f p99=%.2f\n",
              pct_us(read_ns, 0.5), pct_us(read_ns, 0.99), pct_us(write_ns, 0.5),
              pct_us(write_ns, 0.99));
  // The bit times the emulator does not spend: the ADC frame and the DAC frame at their clocks.
  const test::SpiBench& b = bench;
  const double bits_us =
      1e6 * (8.0 * 18.0 / b.config.adc.speed_hz + 8.0 * 3.0 / b.config.dac.speed_hz);
  std::printf(
      "loop rate bound (1 / p99.9 cycle): %.0f Hz on the emulator; %.0f Hz with the SPI "
      "bit times added (%.1f us at %u / %u Hz; the board's ioctl overhead not included; "
      "goal 20000 Hz)\n",
      1e6 / p999, 1e6 / (p999 + bits_us), bits_us, b.config.adc.speed_hz, b.config.dac.speed_hz);
  std::printf("driver: reads=%llu writes=%llu errors=%llu timeouts=%llu stale=%llu bad_data=%llu\n",
              static_cast<unsigned long long>(c.reads), static_cast<unsigned long long>(c.writes),
              static_cast<unsigned long long>(c.errors),
              static_cast<unsigned long long>(c.timeouts), static_cast<unsigned long long>(c.stale),
              static_cast<unsigned long long>(c.bad_data));
  bench.driver.deactivate();
  return armed ? 0 : 1;
}
