#include <fcntl.h>
#include <linux/spi/spidev.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <cerrno>
#include <utility>

#include "selfsense/base/errno_text.hpp"
#include "selfsense/drivers/spi/spi_bus.hpp"

namespace selfsense::drivers::spi {

SpidevBus::SpidevBus(SpidevSettings settings) : settings_(std::move(settings)) {}

SpidevBus::~SpidevBus() {
  close();
}

bool SpidevBus::open(std::string* why) {
  const auto fail = [&](const char* what) {
    if (why != nullptr) *why = settings_.device + ": " + what + ": " + base::errno_text(errno);
    close();
    return false;
  };
  fd_ = ::open(settings_.device.c_str(), O_RDWR | O_CLOEXEC);
  if (fd_ < 0) return fail("open (is spidev bound to this chip select? see docs/drivers/spi.md)");
  const std::uint8_t mode = settings_.mode;
  if (::ioctl(fd_, SPI_IOC_WR_MODE, &mode) < 0) return fail("SPI_IOC_WR_MODE");
  const std::uint8_t bits = 8;
  if (::ioctl(fd_, SPI_IOC_WR_BITS_PER_WORD, &bits) < 0) return fail("SPI_IOC_WR_BITS_PER_WORD");
  const std::uint32_t speed = settings_.speed_hz;
  if (::ioctl(fd_, SPI_IOC_WR_MAX_SPEED_HZ, &speed) < 0) return fail("SPI_IOC_WR_MAX_SPEED_HZ");
  return true;
}

void SpidevBus::close() noexcept {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

bool SpidevBus::transfer(std::span<const std::uint8_t> tx, std::span<std::uint8_t> rx) noexcept {
  if (fd_ < 0 || tx.size() != rx.size()) return false;
  spi_ioc_transfer t{};
  t.tx_buf = reinterpret_cast<std::uintptr_t>(tx.data());
  t.rx_buf = reinterpret_cast<std::uintptr_t>(rx.data());
  t.len = static_cast<std::uint32_t>(tx.size());
  t.speed_hz = settings_.speed_hz;
  t.bits_per_word = 8;
  return ::ioctl(fd_, SPI_IOC_MESSAGE(1), &t) == static_cast<int>(tx.size());
}

}  // namespace selfsense::drivers::spi
