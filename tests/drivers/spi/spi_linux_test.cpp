// The Linux side of the seams (spidev, libgpiod) where CI can reach it: no SPI controller or
// GPIO chip exists here, so these check that each failure is refused and named (device, step,
// errno text), and that an unopened bus or line never pretends to work.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <string>

#include "selfsense/drivers/spi/gpio_line.hpp"
#include "selfsense/drivers/spi/spi_bus.hpp"

namespace {

namespace spi = selfsense::drivers::spi;

TEST(SpidevBus, AMissingDeviceIsNamed) {
  spi::SpidevBus bus({"/nonexistent/spidev0.0", 1000000, 1});
  std::string why;
  EXPECT_FALSE(bus.open(&why));
  EXPECT_NE(why.find("/nonexistent/spidev0.0: open"), std::string::npos) << why;
  EXPECT_NE(why.find("No such file or directory"), std::string::npos) << why;
}

TEST(SpidevBus, ANodeThatIsNotSpidevIsRefusedAtItsFirstIoctl) {
  spi::SpidevBus bus({"/dev/null", 1000000, 1});
  std::string why;
  EXPECT_FALSE(bus.open(&why));
  EXPECT_NE(why.find("/dev/null: SPI_IOC_WR_MODE"), std::string::npos) << why;
}

TEST(SpidevBus, AnUnopenedBusFailsEveryTransfer) {
  spi::SpidevBus bus({"/dev/spidev9.9", 1000000, 1});
  std::array<std::uint8_t, 3> tx{1, 2, 3};
  std::array<std::uint8_t, 3> rx{};
  EXPECT_FALSE(bus.transfer(tx, rx));
}

TEST(GpiodLine, AMissingChipIsNamedAndTheLineNeverWorks) {
  spi::GpiodLine line({"no-such-chip", 3, spi::LineUse::kFallingEdges, false});
  std::string why;
  EXPECT_FALSE(line.open("selfsense-test", &why));
  EXPECT_NE(why.find("no-such-chip line 3: gpiod_chip_open_lookup"), std::string::npos) << why;
  EXPECT_EQ(line.read(), -1);
  EXPECT_FALSE(line.write(true));
  spi::Edge edge;
  EXPECT_EQ(line.wait_edge(1000, &edge), spi::EdgeWait::kError);
}

}  // namespace
