// The seam between the SPI driver and the hardware, at the narrowest place: one full-duplex
// transfer of N bytes on one chip select. Debian's kernel has no simulated SPI controller, so
// tests put chip emulators (tests/support/spi/) behind this interface; everything above it (the
// frames, CRC, register set-up, fault handling, the driver) runs unchanged in CI.
//
// SpidevBus is the Linux implementation: /dev/spidevB.C opened at construction-time open(),
// mode, word size and clock set there, each transfer one ioctl(SPI_IOC_MESSAGE(1)) with
// chip select held for the whole transfer.
#pragma once

#include <cstdint>
#include <span>
#include <string>

namespace selfsense::drivers::spi {

class SpiBus {
 public:
  SpiBus() = default;
  SpiBus(const SpiBus&) = delete;
  SpiBus& operator=(const SpiBus&) = delete;
  SpiBus(SpiBus&&) = delete;
  SpiBus& operator=(SpiBus&&) = delete;
  virtual ~SpiBus() = default;
  // Clocks tx out and rx in at the same time (tx.size() == rx.size(), asserted by callers).
  // False when the transfer failed (the controller or the device node refused it).
  virtual bool transfer(std::span<const std::uint8_t> tx, std::span<std::uint8_t> rx) noexcept = 0;
};

struct SpidevSettings {
  std::string device{};  // /dev/spidev0.0
  std::uint32_t speed_hz{1000000};
  std::uint8_t mode{1};  // SPI mode 0..3 (CPOL, CPHA)
};

class SpidevBus final : public SpiBus {
 public:
  explicit SpidevBus(SpidevSettings settings);
  ~SpidevBus() override;
  SpidevBus(const SpidevBus&) = delete;
  SpidevBus& operator=(const SpidevBus&) = delete;
  SpidevBus(SpidevBus&&) = delete;
  SpidevBus& operator=(SpidevBus&&) = delete;

  // Opens the device and sets mode, 8-bit words and the clock; false with *why (the key, the
  // device, the errno text).
  bool open(std::string* why);
  void close() noexcept;
  // One ioctl(SPI_IOC_MESSAGE(1)): the deliberate exception to "no I/O on the real-time path",
  // because for an ADC on the loop's own SPI bus this transfer IS the sample acquisition
  // (docs/drivers/spi.md). It never allocates; it blocks for the transfer's bit time (18 bytes
  // at 10 MHz: 14.4 us) plus the controller driver's overhead.
  bool transfer(std::span<const std::uint8_t> tx, std::span<std::uint8_t> rx) noexcept override;

 private:
  SpidevSettings settings_;
  int fd_{-1};
};

}  // namespace selfsense::drivers::spi
