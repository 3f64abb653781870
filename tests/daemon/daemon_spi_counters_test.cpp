// The whole daemon (selfsensed's Daemon: loop thread, recorder, control socket, telemetry) on
// the SPI driver against the chip emulators (tests/support/spi/), the ADC injecting CRC errors:
// the errors reach the status reply (counters.driver_crc_errors, counters.driver_events) and the
// Prometheus textfile (selfsense_driver_crc_errors_total, selfsense_driver_events_total), which
// is valid exposition text with the recorder's counters and the fault counts in it.
//
// The loop is paced by the emulated data-ready line, in the emulator's simulated time: it runs
// as fast as the CPU lets it, without real-time scheduling (loop.priority 0: degraded timing).
#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <thread>

#include "daemon/exposition_check.hpp"
#include "daemon/recording_support.hpp"
#include "selfsense/daemon/control_handler.hpp"
#include "selfsense/daemon/daemon.hpp"
#include "support/daemon_plant.hpp"
#include "support/spi/spi_bench.hpp"

namespace selfsense::daemon {
namespace {

constexpr double kRate = 20000.0;  // config/models/sim.yaml's rate

class NoDriverSection final : public DriverSectionReader {
 public:
  void read(io::YamlMap& /*driver*/, const DaemonConfig& /*config*/,
            std::vector<std::string>& /*problems*/) override {}
};

std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(DaemonSpiCounters, CrcErrorsReachTheStatusAndTheTextfile) {
  const testing::ScratchDir dir("spi-counters");
  DaemonConfig config;
  config.loop.rate_hz = kRate;
  config.loop.priority = 0;  // no SCHED_FIFO for a loop that spins in simulated time
  config.loop.allow_degraded_timing = true;
  config.model = std::filesystem::path(SELFSENSE_SOURCE_DIR) / "config/models/sim.yaml";
  config.driver_type = "spi";
  config.control.command_min = 0.0;
  config.control.command_max = 2e6;
  config.recorder.directory = dir.path() / "rec";
  config.recorder.ring_capacity = 1U << 12U;
  config.recorder.flight_recorder_s = 2.0;
  config.socket.path = dir.path() / "run" / "control.sock";
  config.telemetry.prometheus_file = dir.path() / "selfsense.prom";
  config.telemetry.period_s = 0.05;

  // The emulated hardware; the daemon owns a driver of its own on it (maintenance by nobody:
  // two CRC errors stay below crc_errors_to_reinit).
  // The stack's temperature wired on channel 2 (docs/drivers/spi.md, `temp`).
  drivers::spi::SpiConfig spi = test::emulated_spi_config(kRate);
  spi.temp.wired = true;
  test::SpiBench bench(spi, test::daemon_plant(kRate));
  bench.ambient_degc = 31.5;
  auto driver = std::make_unique<drivers::spi::SpiDriver>(
      bench.config,
      drivers::spi::SpiHardware{&bench.adc, &bench.dac, &bench.adc.drdy_line(), &bench.enable,
                                &bench.fault, &bench.clock},
      false);
  NoDriverSection reader;
  Daemon daemon(config, std::move(driver), reader);
  // Before the loop thread starts (its start orders this before every access of its own).
  bench.adc.inject_crc_errors(2);
  std::thread runner([&daemon] { static_cast<void>(daemon.run()); });

  const std::string wanted = "selfsense_driver_crc_errors_total{driver=\"spi\"} 2\n";
  std::string text;
  for (int i = 0; i < 200 && text.find(wanted) == std::string::npos; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
    text = slurp(config.telemetry.prometheus_file);
  }
  ControlHandler handler(daemon);
  const nlohmann::json status = handler.handle(StatusRequest{}, PeerCredentials{});
  daemon.request_stop();
  runner.join();

  EXPECT_NE(text.find(wanted), std::string::npos) << text;
  EXPECT_NE(text.find("selfsense_driver_events_total{driver=\"spi\",event=\"crc_errors\"} 2\n"),
            std::string::npos)
      << text;
  const test::Exposition x = test::check_exposition(text);
  EXPECT_TRUE(x.problems.empty()) << x.problems.front();
  // A corrupted frame is bad data: the loop faulted on it (driver_error) and counted it.
  EXPECT_GE(x.samples.at("selfsense_loop_faults_total").at("fault=driver_error;"), 1.0);
  EXPECT_EQ(x.types.at("selfsense_recorder_rows_written_total"), "counter");
  EXPECT_EQ(x.types.at("selfsense_recorder_write_errors_total"), "counter");
  EXPECT_GT(x.samples.at("selfsense_driver_reads_total").at("driver=spi;"), 100.0);

  ASSERT_TRUE(status.value("ok", false)) << status.dump();
  EXPECT_EQ(status.at("driver"), "spi");
  const nlohmann::json& c = status.at("counters");
  EXPECT_EQ(c.at("driver_crc_errors"), 2);
  EXPECT_EQ(c.at("driver_bad_data"), 2);
  EXPECT_EQ(c.at("driver_events").at("crc_errors"), 2);
  EXPECT_EQ(c.at("driver_events").at("input_crc_errors"), 0);
  EXPECT_EQ(c.at("driver_events").size(), 13U);
  EXPECT_EQ(c.at("driver_events").at("temp_out_of_range"), 0);
  // The temperature as the driver reads it, in the status and the textfile.
  EXPECT_NEAR(status.at("estimate").at("temp").get<double>(), 31.5, 1e-3) << status.dump();
  EXPECT_NEAR(x.samples.at("selfsense_stack_temperature_celsius").at(""), 31.5, 1e-3);
  EXPECT_GT(c.at("driver_reads").get<long long>(), 100);
  EXPECT_TRUE(c.contains("driver_writes"));
  const nlohmann::json& fault = status.at("fault_details").at("driver_error");
  EXPECT_GE(fault.at("count").get<long long>(), 1);
  // The time of the cycle (a recording's t) and what the fault means.
  EXPECT_DOUBLE_EQ(fault.at("first_s").get<double>(),
                   static_cast<double>(fault.at("first_cycle").get<long long>()) / kRate);
  EXPECT_EQ(fault.at("cause"), "the driver reported an error, bad data or a device fault");
}

}  // namespace
}  // namespace selfsense::daemon
