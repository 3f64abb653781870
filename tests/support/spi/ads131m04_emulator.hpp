// An ADS131M04 emulator behind the SpiBus seam, for tests and benches in simulated time.
//
// What it does as the data sheet says (include/selfsense/drivers/spi/ads131m04.hpp lists the
// facts):
//   - 24-bit words, frames of 6 words; the response word answers the previous frame's command
//     (NULL: STATUS with DRDY3..0 set for a conversion not yet read); a CRC-16-CCITT word closes
//     every output frame; with MODE.RX_CRC_EN the input CRC is checked, a mismatch sets
//     STATUS.CRC_ERR and the command is dropped;
//   - RESET (answered FF24h, registers to their reset values, STATUS.RESET set until MODE is
//     written with RESET 0), STANDBY / WAKEUP, single-register RREG and WREG (ID and STATUS read
//     only), register map 00h..3Fh;
//   - conversions every 2 * OSR / f_CLKIN on the simulated clock, each sampling the four
//     analog inputs given by a callback (the simulated transducer behind its front end); DRDY
//     falls at each conversion and rises when a frame is read (drdy_line()).
// Fault injection (explicit calls): CRC errors on the next N output frames, a stuck converter
// (codes frozen while DRDY keeps running), a register that reads back wrong, a spontaneous
// reset, a dead bus (transfers fail).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <span>

#include "selfsense/drivers/spi/ads131m04.hpp"
#include "selfsense/drivers/spi/gpio_line.hpp"
#include "selfsense/drivers/spi/spi_bus.hpp"
#include "selfsense/runtime/pacer.hpp"

namespace selfsense::test {

class Ads131m04Emulator final : public drivers::spi::SpiBus {
 public:
  // Input voltages of channels 0..3 at a conversion instant [ns]. Called once per conversion
  // (not on the driver's thread: from transfer() and the DRDY wait, as time passes).
  using Inputs = std::function<std::array<double, 4>(std::int64_t t_ns)>;

  Ads131m04Emulator(runtime::SimulatedClock& clock, double clkin_hz, Inputs inputs);

  bool transfer(std::span<const std::uint8_t> tx, std::span<std::uint8_t> rx) noexcept override;
  // The DRDY pin (active low) as a GPIO line: falling edges at each conversion.
  [[nodiscard]] drivers::spi::GpioLine& drdy_line() noexcept { return drdy_; }

  // Fault injection.
  void inject_crc_errors(int frames) noexcept { crc_errors_ = frames; }
  void set_stuck(bool stuck) noexcept { stuck_ = stuck; }
  void corrupt_readback(std::uint8_t address, std::uint16_t xor_mask) noexcept {
    corrupt_address_ = address;
    corrupt_xor_ = xor_mask;
  }
  void spontaneous_reset() noexcept;
  void set_dead(bool dead) noexcept { dead_ = dead; }

  [[nodiscard]] std::uint16_t reg(std::uint8_t address) const noexcept { return regs_.at(address); }
  [[nodiscard]] double data_rate_hz() const noexcept;
  [[nodiscard]] long conversions() const noexcept { return conversions_; }
  [[nodiscard]] long frames() const noexcept { return frames_; }
  [[nodiscard]] long rejected_commands() const noexcept { return rejected_; }

 private:
  class DrdyLine final : public drivers::spi::GpioLine {
   public:
    explicit DrdyLine(Ads131m04Emulator& adc) : adc_(&adc) {}
    int read() noexcept override;
    bool write(bool /*high*/) noexcept override { return false; }
    drivers::spi::EdgeWait wait_edge(std::int64_t timeout_ns,
                                     drivers::spi::Edge* edge) noexcept override;

   private:
    Ads131m04Emulator* adc_;
  };

  void reset_registers() noexcept;
  void restart_conversions() noexcept;
  // Runs every conversion due up to now.
  void convert_until(std::int64_t now) noexcept;
  [[nodiscard]] std::int64_t period_ns() const noexcept;
  [[nodiscard]] std::uint16_t status() const noexcept;
  void execute(std::span<const std::uint8_t> tx) noexcept;

  runtime::SimulatedClock* clock_;
  double clkin_hz_;
  Inputs inputs_;
  DrdyLine drdy_{*this};
  std::array<std::uint16_t, drivers::spi::ads131m04::kRegCount> regs_{};
  std::array<std::int32_t, 4> codes_{};
  std::int64_t next_conversion_ns_{0};
  std::int64_t last_edge_taken_ns_{-1};
  std::uint16_t pending_{0};
  bool pending_is_status_{true};
  bool new_data_{false};
  bool reset_flag_{true};
  bool crc_err_flag_{false};
  bool standby_{false};
  bool stuck_{false};
  bool dead_{false};
  int crc_errors_{0};
  std::uint8_t corrupt_address_{0xFF};
  std::uint16_t corrupt_xor_{0};
  long conversions_{0};
  long frames_{0};
  long rejected_{0};
};

}  // namespace selfsense::test
