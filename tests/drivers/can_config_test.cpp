// The CAN driver's section of the daemon configuration (driver.type can), as selfsensed and
// `selfsense check-config` read it: the shipped config/can-sim.yaml loads with the layout it
// describes, and every kind of mistake is named by its key. The driver itself needs a kernel
// with SocketCAN: without one, activate() fails with a message and read()/write() say so.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "selfsense/daemon/config.hpp"
#include "selfsense/drivers/can/can_driver.hpp"
#include "selfsense/drivers/registry/registry.hpp"
#include "support/config_edits.hpp"

namespace {

using selfsense::daemon::ConfigResult;
using selfsense::daemon::load_config;
using selfsense::drivers::Registry;
namespace can = selfsense::drivers::can;

const std::filesystem::path kConfigDir = selfsense::test::shipped_config_dir();

// can-sim.yaml with each (from, to) replaced once, loaded from a scratch directory.
ConfigResult load_with(const selfsense::test::Edits& edits, Registry& registry) {
  return selfsense::test::load_shipped_with("can-sim.yaml", edits, registry, ".test-can.yaml");
}

// The problems joined, for messages and searching.
std::string joined(const ConfigResult& r) {
  std::string all;
  for (const std::string& p : r.problems)
    all += p + "\n";
  return all;
}

TEST(CanConfig, ShippedConfigurationLoadsWithItsLayout) {
  Registry registry;
  const ConfigResult r = load_config(kConfigDir / "can-sim.yaml", &registry);
  ASSERT_TRUE(r.ok()) << joined(r);
  EXPECT_EQ(r.config.driver_type, "can");
  const can::CanConfig& c = registry.can_config();
  EXPECT_EQ(c.interface, "vcan0");
  EXPECT_FALSE(c.fd);
  EXPECT_EQ(c.e.frame, (can::FrameId{0x101, false}));
  EXPECT_EQ(c.e.signal.start_bit, 0U);
  EXPECT_EQ(c.d.signal.start_bit, 32U);  // byte: 4, little endian
  EXPECT_EQ(c.d.signal.scale, 1e-9);
  EXPECT_EQ(c.s_ref.signal.order, can::ByteOrder::kBig);
  EXPECT_EQ(c.s_ref.signal.start_bit, 7U);
  EXPECT_EQ(c.command.frame, (can::FrameId{0x18FF0001, true}));
  EXPECT_TRUE(c.has_references());
  EXPECT_TRUE(c.has_temperature());
  EXPECT_EQ(c.temp.frame, (can::FrameId{0x103, false}));
  EXPECT_EQ(c.temp.signal.length, 16U);
  EXPECT_TRUE(c.temp.signal.is_signed);
  EXPECT_EQ(c.temp.signal.scale, 0.01);
  EXPECT_EQ(c.temp_timeout_ms, 1000.0);
  const std::vector<can::FrameLayout> frames = c.input_frames();
  ASSERT_EQ(frames.size(), 3U);
  EXPECT_EQ(frames[0].bytes, 8U);
  EXPECT_EQ(frames[1].bytes, 8U);
  EXPECT_EQ(frames[2].id, (can::FrameId{0x103, false}));
  EXPECT_EQ(frames[2].bytes, 2U);
  const auto driver = registry.create();
  ASSERT_NE(driver, nullptr);
  EXPECT_EQ(driver->name(), "can");
  EXPECT_TRUE(driver->has_references());
  EXPECT_TRUE(driver->has_temperature());
}

TEST(CanConfig, TheTemperatureIsOptional) {
  Registry registry;
  const ConfigResult r = load_with({{"    temp: {id: 0x103", "    # temp: {id: 0x103"},
                                    {"           scale: 0.01}", "           # scale: 0.01}"}},
                                   registry);
  ASSERT_TRUE(r.ok()) << joined(r);
  EXPECT_FALSE(registry.can_config().has_temperature());
  EXPECT_EQ(registry.can_config().input_frames().size(), 2U);
  const auto driver = registry.create();
  ASSERT_NE(driver, nullptr);
  EXPECT_FALSE(driver->has_temperature());
}

TEST(CanConfig, EveryMistakeIsNamedByItsKey) {
  const std::vector<std::pair<std::pair<std::string, std::string>, std::string>> cases{
      {{"interface: vcan0 ", "interface: a-very-long-name0 "}, "driver.interface: "},
      {{"rx_timeout_ms: 50 ", "rx_timeout_ms: 0.5 "}, "driver.rx_timeout_ms: "},
      {{"temp_timeout_ms: 1000 ", "temp_timeout_ms: 90000 "}, "driver.temp_timeout_ms: "},
      {{"temp: {id: 0x103, byte: 0", "temp: {id: 0x102, byte: 0"},
       "driver.signals.temp: overlaps signal s_ref in frame 0x102"},
      {{"temp: {id: 0x103, byte: 0, length: 16", "temp: {id: 0x103, byte: 0, length: 80"},
       "driver.signals.temp.length: "},
      {{"byte: 4, length: 32", "byte: 2, length: 32"},
       "driver.signals.d: overlaps signal e in frame 0x101"},
      {{"byte: 4, length: 32", "byte: 5, length: 32"}, "driver.signals.d.byte: "},
      {{"start_bit: 39", "start_bit: 40"}, "driver.signals.t_ref.start_bit: "},
      {{"length: 32, byte_order: big", "length: 0, byte_order: big"},
       "driver.signals.s_ref.length: "},
      {{"byte_order: big", "byte_order: middle"}, "driver.signals.s_ref.byte_order: "},
      {{"scale: 1.0e-9, offset", "scale: 0.0, offset"}, "driver.signals.d.scale: "},
      {{"id: 0x18FF0001, extended: true", "id: 0x18FF0001, extended: false"},
       "driver.signals.command.id: 0x18FF0001 does not fit a 11-bit standard identifier"},
      {{"id: 0x18FF0001, extended: true", "id: 0x102, extended: false"},
       "driver.signals.command.id: 0x102 is also the frame of input s_ref"},
      {{"e: {id: 0x101, extended: false, byte: 0,",
        "e: {id: 0x101, extended: false, byte: 0, start_bit: 0,"},
       "driver.signals.e: give exactly one of byte"},
      {{"    t_ref: {id: 0x102", "    t_ref_unused: {id: 0x102"}, "t_ref_unused"},
      {{"fd: false", "fd: maybe"}, "driver.fd"},
      {{"type: can", "type: canopen"}, "driver.type: 'canopen' is not one of simulated, can"},
  };
  for (const auto& [edit, expected] : cases) {
    Registry registry;
    const ConfigResult r = load_with({edit}, registry);
    EXPECT_NE(joined(r).find(expected), std::string::npos)
        << edit.second << "\nexpected: " << expected << "\ngot:\n"
        << joined(r);
    // Every problem is located: the file and a line.
    for (const std::string& p : r.problems)
      EXPECT_NE(p.find(".test-can.yaml:"), std::string::npos) << p;
  }
}

TEST(CanConfig, FdAllowsSixtyFourByteFrames) {
  Registry registry;
  const ConfigResult r =
      load_with({{"fd: false", "fd: true"}, {"start_bit: 39", "start_bit: 8"}}, registry);
  // start_bit 8 (big endian) overlaps s_ref in bytes 0..3: a layout error, not a size error.
  EXPECT_NE(joined(r).find("driver.signals.t_ref: overlaps signal s_ref"), std::string::npos)
      << joined(r);
  Registry fd;
  const ConfigResult ok =
      load_with({{"fd: false", "fd: true"}, {"start_bit: 39", "start_bit: 487"}}, fd);
  EXPECT_TRUE(ok.ok()) << joined(ok);
  EXPECT_EQ(fd.can_config().input_frames()[1].bytes, 64U);
  EXPECT_EQ(fd.can_config().frame_length(9), 12U);
}

TEST(CanConfig, TheBusThreadPriorityIsChecked) {
  Registry registry;
  const ConfigResult ok = load_with({{"  priority: 70 ", "  priority: 0 "}}, registry);
  ASSERT_TRUE(ok.ok()) << joined(ok);
  EXPECT_EQ(registry.can_config().priority, 0);
  Registry bad;
  const ConfigResult r = load_with({{"  priority: 70 ", "  priority: 120 "}}, bad);
  EXPECT_NE(joined(r).find("driver.priority: 120 must be 0 (normal) or within [1, 99]"),
            std::string::npos)
      << joined(r);
}

TEST(CanDriver, WithoutActivationNothingHappens) {
  Registry registry;
  ASSERT_TRUE(load_config(kConfigDir / "can-sim.yaml", &registry).ok());
  const auto driver = registry.create();
  selfsense::runtime::InputSample in;
  EXPECT_EQ(driver->read(in), selfsense::runtime::DriverStatus::kNotActive);
  EXPECT_EQ(driver->write({1.0}), selfsense::runtime::DriverStatus::kNotActive);
  std::string why;
  EXPECT_FALSE(driver->activate(&why));
  EXPECT_NE(why.find("activate() before configure()"), std::string::npos) << why;
  ASSERT_TRUE(driver->configure({1e-3}, &why)) << why;
  // On a kernel without SocketCAN (the CI host) or without the interface, activate() names why.
  if (!driver->activate(&why)) {
    EXPECT_TRUE(why.find("socket(PF_CAN") != std::string::npos ||
                why.find("driver.interface: vcan0") != std::string::npos)
        << why;
    EXPECT_EQ(driver->read(in), selfsense::runtime::DriverStatus::kNotActive);
  }
  driver->deactivate();
}

}  // namespace
