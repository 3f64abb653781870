// The SPI driver's section of the daemon configuration (driver.type spi), as selfsensed and
// `selfsense check-config` read it: the shipped config/spi-ads131m04.yaml loads through the
// registry, and each kind of mistake is named by its key.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "selfsense/daemon/config.hpp"
#include "selfsense/drivers/registry/registry.hpp"
#include "selfsense/drivers/spi/spi_driver.hpp"
#include "support/config_edits.hpp"

namespace {

using selfsense::daemon::ConfigResult;
using selfsense::daemon::load_config;
using selfsense::drivers::Registry;
namespace spi = selfsense::drivers::spi;

const std::filesystem::path kConfigDir = selfsense::test::shipped_config_dir();

// spi-ads131m04.yaml with each (from, to) replaced once, loaded from a scratch directory.
ConfigResult load_with(const selfsense::test::Edits& edits, Registry& registry) {
  return selfsense::test::load_shipped_with("spi-ads131m04.yaml", edits, registry,
                                            ".test-spi.yaml");
}

std::string joined(const ConfigResult& r) {
  std::string all;
  for (const std::string& p : r.problems)
    all += p + "\n";
  return all;
}

TEST(SpiConfig, ShippedConfigurationLoadsAndBuildsTheDriver) {
  Registry registry;
  const ConfigResult r = load_config(kConfigDir / "spi-ads131m04.yaml", &registry);
  ASSERT_TRUE(r.ok()) << joined(r);
  EXPECT_EQ(r.config.driver_type, "spi");
  const spi::SpiConfig& c = registry.spi_config();
  EXPECT_EQ(c.pace, spi::Pace::kDrdy);
  EXPECT_DOUBLE_EQ(c.adc.data_rate_hz(), 20000.0);
  EXPECT_EQ(c.adc.osr_code(), 0);
  EXPECT_EQ(c.d.channel, 1);
  EXPECT_TRUE(c.gpio.fault.active_low);
  EXPECT_EQ(c.gpio.drdy.line, 25);
  const auto driver = registry.create();
  EXPECT_EQ(driver->name(), "spi");
  // Scaling: 1 V at the ADC through the 125:1 divider is 125 V on a 60 um layer.
  EXPECT_NEAR(c.field_of(1.0), 125.0 / 60e-6, 1e-3);
  EXPECT_NEAR(c.displacement_of(-1.0), 330e-6 / (167 * 25e-6), 1e-12);
  EXPECT_NEAR(c.dac_volts_of(2e6), 2e6 * 60e-6 / 30.0, 1e-12);
  EXPECT_TRUE(c.temp.wired);
  EXPECT_EQ(c.temp.channel, 2);
  EXPECT_NEAR(c.temperature_of(0.25 + 0.005 * 42.0), 42.0, 1e-9);
  EXPECT_TRUE(driver->has_temperature());
}

TEST(SpiConfig, TheTemperatureChannelIsOptional) {
  Registry registry;
  const ConfigResult r = load_with({{"  temp:  ", "  temp_unwired:  "}}, registry);
  EXPECT_NE(joined(r).find("temp_unwired"), std::string::npos) << joined(r);
  Registry none;
  const ConfigResult ok =
      load_with({{"  temp:  ", "  # temp:  "},
                 {"    channel: 2 ", "    # channel: 2 "},
                 {"    pga_gain: 1\n    volts_at_0_degc", "    # pga_gain: 1\n    volts_at_0_degc"},
                 {"    volts_at_0_degc: 0.25 ", "    # volts_at_0_degc: 0.25 "},
                 {"    volts_per_degc: 0.005 ", "    # volts_per_degc: 0.005 "},
                 {"    range_degc: ", "    # range_degc: "}},
                none);
  ASSERT_TRUE(ok.ok()) << joined(ok);
  EXPECT_FALSE(none.spi_config().temp.wired);
  EXPECT_FALSE(none.create()->has_temperature());
}

TEST(SpiConfig, ProblemsNameTheirKeys) {
  const std::vector<std::pair<std::pair<std::string, std::string>, std::string>> cases{
      {{"osr: 128 ", "osr: 100 "}, "driver.adc.osr: 100 is not one of 128"},
      {{"osr: 128 ", "osr: 256 "},
       "driver.adc.osr: the data rate clkin_hz / 2 / osr = 10000 Hz "
       "must equal loop.rate_hz 20000 when pace is drdy"},
      {{"divider: 125.0", "divider: 50.0"}, "driver.e.range_v_per_m: 2400000 V/m is 2.88 V"},
      {{"pga_gain: 1  ", "pga_gain: 3  "}, "driver.e.pga_gain: 3 is not one of 1, 2, 4"},
      {{"channel: 1", "channel: 0"}, "driver.d.channel: 0 is also e.channel"},
      {{"device: /dev/spidev0.1", "device: /dev/spidev0.0"},
       "driver.dac.device: the DAC needs its own chip select"},
      {{"feedback_capacitance_f: 330.0e-6", "feedback_capacitance_f: 100.0e-6"},
       "driver.d.range_c_per_m2: 0.09 C/m^2"},
      {{"clkin_hz: 5120000", "clkin_hz: 9000000"}, "driver.adc.clkin_hz: 9e+06 must be within"},
      {{"full_scale_v: 5.0", "full_scale_v: -1"}, "driver.dac.full_scale_v: -1 must be within"},
      {{"channel: 2 ", "channel: 1 "}, "driver.temp.channel: 1 is also the channel of E or D"},
      {{"volts_per_degc: 0.005", "volts_per_degc: 0.01"},
       "driver.temp.range_degc: 150 degC is 1.75 V at the ADC, outside its full scale"},
      {{"volts_per_degc: 0.005", "volts_per_degc: 0.0"},
       "driver.temp.volts_per_degc: 0 must be finite and not 0"},
      {{"range_degc: [-40.0, 150.0]", "range_degc: [150.0, -40.0]"},
       "driver.temp.range_degc: needs min < max"},
  };
  for (const auto& [edit, expected] : cases) {
    Registry registry;
    const ConfigResult r = load_with({edit}, registry);
    EXPECT_FALSE(r.ok()) << edit.second;
    EXPECT_NE(joined(r).find(expected), std::string::npos) << joined(r);
    // Each problem is located "FILE:LINE: driver....".
    EXPECT_NE(joined(r).find(".test-spi.yaml:"), std::string::npos) << joined(r);
  }
}

TEST(SpiConfig, EveryProblemIsNamedAtOnce) {
  Registry registry;
  const ConfigResult r =
      load_with({{"osr: 128 ", "osr: 100 "}, {"divider: 125.0", "divider: 50.0"}}, registry);
  EXPECT_NE(joined(r).find("driver.adc.osr"), std::string::npos) << joined(r);
  EXPECT_NE(joined(r).find("driver.e.range_v_per_m"), std::string::npos) << joined(r);
}

TEST(SpiConfig, UnknownKeysAndWordsAreRefused) {
  Registry a;
  const ConfigResult r = load_with({{"input_crc: true", "input_crc: true\n    crc: 1"}}, a);
  EXPECT_NE(joined(r).find("driver.adc.crc"), std::string::npos) << joined(r);
  Registry b;
  const ConfigResult p = load_with({{"pace: drdy ", "pace: irq "}}, b);
  EXPECT_NE(joined(p).find("driver.pace: 'irq' is not one of drdy, timer"), std::string::npos)
      << joined(p);
  Registry c;
  const ConfigResult t = load_with({{"pace: drdy ", "pace: timer "}}, c);
  EXPECT_TRUE(t.ok()) << joined(t);
}

TEST(SpiDriver, WithoutHardwareActivateNamesTheDevice) {
  Registry registry;
  ASSERT_TRUE(load_config(kConfigDir / "spi-ads131m04.yaml", &registry).ok());
  spi::SpiConfig c = registry.spi_config();
  c.adc.device = "/nonexistent/spidev9.9";
  spi::SpiDriver driver(c);
  selfsense::runtime::InputSample in;
  EXPECT_EQ(driver.read(in), selfsense::runtime::DriverStatus::kNotActive);
  EXPECT_EQ(driver.write({1.0}), selfsense::runtime::DriverStatus::kNotActive);
  std::string why;
  ASSERT_TRUE(driver.configure({5e-5}, &why)) << why;
  EXPECT_FALSE(driver.activate(&why));
  EXPECT_NE(why.find("driver.adc.device: /nonexistent/spidev9.9: open"), std::string::npos) << why;
  EXPECT_EQ(driver.read(in), selfsense::runtime::DriverStatus::kNotActive);
  driver.deactivate();
}

}  // namespace
