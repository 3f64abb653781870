// The TI DAC8563's SPI protocol (dual 16-bit voltage DAC), pure: the 24-bit write frame and the
// command set the driver uses. No I/O.
//
// Facts from the data sheet (SLAS719, "DAC856x ... 16-bit dual, low-power, buffered voltage
// output DACs with 2.5-V, 4-ppm/°C internal reference"), as this code uses them:
//   SPI, data taken on the falling edge of SCLK (mode 1, CPOL 0 CPHA 1), MSB first, SYNC (chip
//   select) low for 24 bits. A frame: DB23..22 don't care, DB21..19 command C2..C0,
//   DB18..16 address A2..A0, DB15..0 data. The DAC does not answer (no readback).
//   Commands: 000 write input register n; 001 update DAC register n (software LDAC);
//   010 write input register n, update all; 011 write input register n and update DAC n;
//   100 power up/down (data: PD1 PD0 at DB5..4, DAC-B at DB1, DAC-A at DB0; 00 = up);
//   101 software reset (DB0 = 1: every register to its power-on value); 110 LDAC register
//   (DB1 DB0 = 1: that DAC ignores the LDAC pin); 111 internal reference (DB0 = 1: on).
//   Addresses: 000 DAC-A, 001 DAC-B, 111 both.
//   Output: V = V_full_scale * code / 65536 with code straight binary (V_full_scale = V_REF times
//   the output gain, as wired and set: 2.5 V internal reference, gain 2 after enabling it).
#pragma once

#include <array>
#include <cstdint>

namespace selfsense::drivers::spi::dac8563 {

using Frame = std::array<std::uint8_t, 3>;

enum class Command : std::uint8_t {
  kWriteInput = 0,
  kUpdate = 1,
  kWriteInputUpdateAll = 2,
  kWriteUpdate = 3,
  kPower = 4,
  kReset = 5,
  kLdac = 6,
  kReference = 7,
};

inline constexpr std::uint8_t kDacA = 0;
inline constexpr std::uint8_t kDacB = 1;
inline constexpr std::uint8_t kBoth = 7;

[[nodiscard]] constexpr Frame frame(Command c, std::uint8_t address, std::uint16_t data) noexcept {
  return {static_cast<std::uint8_t>(((static_cast<unsigned>(c) & 7U) << 3U) | (address & 7U)),
          static_cast<std::uint8_t>(data >> 8U), static_cast<std::uint8_t>(data & 0xFFU)};
}

struct Decoded {
  Command command{Command::kWriteInput};
  std::uint8_t address{0};
  std::uint16_t data{0};
};
[[nodiscard]] constexpr Decoded decode(const Frame& f) noexcept {
  return {static_cast<Command>((f[0] >> 3U) & 7U), static_cast<std::uint8_t>(f[0] & 7U),
          static_cast<std::uint16_t>((f[1] << 8U) | f[2])};
}

// The start-up sequence: reset, both DACs powered up, LDAC pin ignored (a write updates the
// output at once), and the internal reference on or off.
[[nodiscard]] constexpr std::array<Frame, 4> startup(bool internal_reference) noexcept {
  return {frame(Command::kReset, 0, 1), frame(Command::kPower, kBoth, 0x0003),
          frame(Command::kLdac, 0, 0x0003),
          frame(Command::kReference, 0, internal_reference ? 1U : 0U)};
}

// Code for a voltage on a DAC of that full scale: rounded and clipped to [0, 65535]; clipped
// tells whether it was.
struct Code {
  std::uint16_t code{0};
  bool clipped{false};
};
[[nodiscard]] Code code_of(double volts, double full_scale_v) noexcept;
[[nodiscard]] constexpr double volts(std::uint16_t code, double full_scale_v) noexcept {
  return full_scale_v * static_cast<double>(code) / 65536.0;
}

}  // namespace selfsense::drivers::spi::dac8563
