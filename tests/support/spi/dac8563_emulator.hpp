// A DAC8563 emulator behind the SpiBus seam: decodes every 24-bit frame the way the data sheet
// defines it (command, address, data; see include/selfsense/drivers/spi/dac8563.hpp) into input and
// DAC registers, power state, LDAC mask and reference, and gives the output voltage the amplifier
// sees. Frames of another length are counted as malformed and change nothing.
#pragma once

#include <array>
#include <cstdint>
#include <span>

#include "selfsense/drivers/spi/dac8563.hpp"
#include "selfsense/drivers/spi/spi_bus.hpp"

namespace selfsense::test {

class Dac8563Emulator final : public drivers::spi::SpiBus {
 public:
  explicit Dac8563Emulator(double full_scale_v) : full_scale_v_(full_scale_v) {}

  bool transfer(std::span<const std::uint8_t> tx, std::span<std::uint8_t> rx) noexcept override {
    namespace dac = drivers::spi::dac8563;
    if (dead_) return false;
    for (std::uint8_t& b : rx)
      b = 0;  // SDO is not driven
    if (tx.size() != 3) {
      ++malformed_;
      return true;
    }
    ++frames_;
    const dac::Decoded d = dac::decode({tx[0], tx[1], tx[2]});
    const auto each = [&](auto&& f) {
      if (d.address == dac::kBoth) {
        f(0);
        f(1);
      } else if (d.address <= 1) {
        f(d.address);
      }
    };
    switch (d.command) {
      case dac::Command::kWriteInput:
        each([&](int i) { input_.at(static_cast<std::size_t>(i)) = d.data; });
        each([&](int i) {
          if (((static_cast<unsigned>(ldac_mask_) >> static_cast<unsigned>(i)) & 1U) != 0U) {
            update(i);
          }
        });
        break;
      case dac::Command::kUpdate:
        each([&](int i) { update(i); });
        break;
      case dac::Command::kWriteInputUpdateAll:
        each([&](int i) { input_.at(static_cast<std::size_t>(i)) = d.data; });
        update(0);
        update(1);
        break;
      case dac::Command::kWriteUpdate:
        each([&](int i) {
          input_.at(static_cast<std::size_t>(i)) = d.data;
          update(i);
        });
        break;
      case dac::Command::kPower:
        for (int i = 0; i < 2; ++i) {
          if (((static_cast<unsigned>(d.data) >> static_cast<unsigned>(i)) & 1U) != 0U)
            powered_.at(static_cast<std::size_t>(i)) = (d.data & 0x30U) == 0U;
        }
        break;
      case dac::Command::kReset:
        input_ = {};
        dac_ = {};
        if ((d.data & 1U) != 0U) {
          powered_ = {true, true};
          ldac_mask_ = 0;
          reference_ = false;
        }
        break;
      case dac::Command::kLdac:
        ldac_mask_ = static_cast<std::uint8_t>(d.data & 3U);
        break;
      case dac::Command::kReference:
        reference_ = (d.data & 1U) != 0U;
        break;
    }
    return true;
  }

  // The output voltage of DAC-A (0) or DAC-B (1).
  [[nodiscard]] double volts(int output) const noexcept {
    const auto i = static_cast<std::size_t>(output);
    return powered_.at(i) ? drivers::spi::dac8563::volts(dac_.at(i), full_scale_v_) : 0.0;
  }
  [[nodiscard]] std::uint16_t code(int output) const noexcept {
    return dac_.at(static_cast<std::size_t>(output));
  }
  [[nodiscard]] bool reference_on() const noexcept { return reference_; }
  [[nodiscard]] std::uint8_t ldac_mask() const noexcept { return ldac_mask_; }
  [[nodiscard]] long frames() const noexcept { return frames_; }
  [[nodiscard]] long malformed() const noexcept { return malformed_; }
  void set_dead(bool dead) noexcept { dead_ = dead; }

 private:
  void update(int i) noexcept {
    const auto k = static_cast<std::size_t>(i);
    dac_.at(k) = input_.at(k);
  }

  double full_scale_v_;
  std::array<std::uint16_t, 2> input_{};
  std::array<std::uint16_t, 2> dac_{};
  std::array<bool, 2> powered_{true, true};
  std::uint8_t ldac_mask_{0};
  bool reference_{false};
  bool dead_{false};
  long frames_{0};
  long malformed_{0};
};

}  // namespace selfsense::test
