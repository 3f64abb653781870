// The GPIO seam of the SPI driver: one line, read, written or waited on for an edge. Debian's
// kernel has no simulated GPIO chip (gpio-sim is not built in its generic kernel for the test
// hosts, and needs root and configfs), so tests put emulated lines (tests/support/spi/) behind
// this interface, driven by the chip emulators' simulated clock.
//
// GpiodLine is the Linux implementation over libgpiod 1.6 (Debian 12's; the character device
// /dev/gpiochipN). Levels are physical (1 = high); which level means "active" is the driver's
// configuration (driver.gpio.*.active_low), not the line's.
#pragma once

#include <cstdint>
#include <string>

struct gpiod_chip;  // libgpiod
struct gpiod_line;

namespace selfsense::drivers::spi {

enum class EdgeWait : std::uint8_t { kEdge, kTimeout, kError };

struct Edge {
  bool rising{false};
  std::int64_t timestamp_ns{0};  // the kernel's stamp of the edge (CLOCK_MONOTONIC on >= 5.7)
};

class GpioLine {
 public:
  GpioLine() = default;
  GpioLine(const GpioLine&) = delete;
  GpioLine& operator=(const GpioLine&) = delete;
  GpioLine(GpioLine&&) = delete;
  GpioLine& operator=(GpioLine&&) = delete;
  virtual ~GpioLine() = default;
  // The level (0 or 1); -1 on an error.
  virtual int read() noexcept = 0;
  // Drives an output line; false on an error.
  virtual bool write(bool high) noexcept = 0;
  // Waits up to timeout_ns for the next edge the line was requested for and takes it (one edge
  // per call, oldest first).
  virtual EdgeWait wait_edge(std::int64_t timeout_ns, Edge* edge) noexcept = 0;
};

enum class LineUse : std::uint8_t {
  kInput,         // read()
  kOutput,        // write()
  kFallingEdges,  // wait_edge() on falling edges (and read())
  kBothEdges,     // wait_edge() on both edges (and read())
};

struct GpiodSettings {
  std::string chip{};  // gpiochip0, /dev/gpiochip0, a label or a number (gpiod_chip_open_lookup)
  unsigned offset{0};
  LineUse use{LineUse::kInput};
  bool initial{false};  // an output's level at request
};

class GpiodLine final : public GpioLine {
 public:
  explicit GpiodLine(GpiodSettings settings);
  ~GpiodLine() override;
  GpiodLine(const GpiodLine&) = delete;
  GpiodLine& operator=(const GpiodLine&) = delete;
  GpiodLine(GpiodLine&&) = delete;
  GpiodLine& operator=(GpiodLine&&) = delete;

  // Opens the chip and requests the line as `consumer`; false with *why.
  bool open(const char* consumer, std::string* why);
  void close() noexcept;
  int read() noexcept override;
  bool write(bool high) noexcept override;
  EdgeWait wait_edge(std::int64_t timeout_ns, Edge* edge) noexcept override;

 private:
  GpiodSettings settings_;
  gpiod_chip* chip_{nullptr};
  gpiod_line* line_{nullptr};
};

}  // namespace selfsense::drivers::spi
