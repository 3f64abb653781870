// The TI ADS131M04's SPI protocol (24-bit, 4 simultaneously sampled channels), pure: commands,
// frames, CRC, registers and conversion codes. No I/O; the driver (spi_driver.hpp) and the chip
// emulator of the tests (tests/support/spi/) both use it, the emulator only for the constants
// and the CRC, so that a wrong frame layout here shows up as a failed test, not as agreement.
//
// Facts from the data sheet (SBAS962, "ADS131M04 4-Channel, Simultaneously-Sampling, 24-Bit
// ADC"), as this code uses them:
//   SPI mode 1 (CPOL 0, CPHA 1), MSB first. A frame is words of 24 bits (WLENGTH 01b, the
//   default; the only word size this code speaks). 16-bit items (commands, responses, register
//   values, CRC) sit MSB-aligned in a word, the low byte padded with 0.
//   DIN  (host -> ADC): command word, [register data words of a WREG], input CRC word, zeros.
//   DOUT (ADC -> host): response word, channel 0..3 (24-bit two's complement), output CRC word.
//   The response word answers the command of the PREVIOUS frame (NULL: the STATUS register).
//   CRC: CRC-16-CCITT, polynomial x^16 + x^12 + x^5 + 1 (0x1021), initial value 0xFFFF, MSB
//   first, no reflection, no final XOR (CRC_TYPE 0), over every byte of the frame before the CRC
//   word, padding included. The ADC checks the input CRC only when MODE.RX_CRC_EN is set; a
//   mismatch sets STATUS.CRC_ERR and the command is not executed.
//   Commands: NULL 0000h, RESET 0011h (answer FF24h), STANDBY 0022h, WAKEUP 0033h,
//   LOCK 0555h, UNLOCK 0655h, RREG 101a aaaa annn nnnn, WREG 011a aaaa annn nnnn (a: register
//   address, n: number of registers - 1). A WREG is answered by 010a aaaa ammm mmmm (m: number
//   of registers written - 1); a single-register RREG by the register's value. This code reads
//   and writes one register per command.
//   Full scale: +-1.2 V / PGA gain; code = V * gain / 1.2 V * 2^23, clipped to
//   [-2^23, 2^23 - 1]. Data rate = f_CLKIN / 2 / OSR.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace selfsense::drivers::spi::ads131m04 {

inline constexpr std::size_t kWordBytes = 3;
inline constexpr std::size_t kChannels = 4;
inline constexpr std::size_t kFrameWords = 2 + kChannels;  // response, 4 channels, CRC
inline constexpr std::size_t kFrameBytes = kFrameWords * kWordBytes;
using Frame = std::array<std::uint8_t, kFrameBytes>;

// Commands.
inline constexpr std::uint16_t kNull = 0x0000;
inline constexpr std::uint16_t kReset = 0x0011;
inline constexpr std::uint16_t kStandby = 0x0022;
inline constexpr std::uint16_t kWakeup = 0x0033;
inline constexpr std::uint16_t kResetAnswer = 0xFF24;  // "FF24h" for the 4-channel device

// Registers.
inline constexpr std::uint8_t kRegId = 0x00;
inline constexpr std::uint8_t kRegStatus = 0x01;
inline constexpr std::uint8_t kRegMode = 0x02;
inline constexpr std::uint8_t kRegClock = 0x03;
inline constexpr std::uint8_t kRegGain = 0x04;
inline constexpr std::uint8_t kRegCfg = 0x06;
inline constexpr std::uint8_t kRegCount = 0x40;  // addresses 00h..3Fh

// Reset values.
inline constexpr std::uint16_t kIdValue = 0x2400;  // high byte 24h (CHANCNT 4); low byte varies
inline constexpr std::uint16_t kStatusResetValue = 0x0500;
inline constexpr std::uint16_t kModeResetValue = 0x0510;
inline constexpr std::uint16_t kClockResetValue = 0x0F0E;

// STATUS bits.
inline constexpr std::uint16_t kStatusLock = 1U << 15U;
inline constexpr std::uint16_t kStatusResync = 1U << 14U;
inline constexpr std::uint16_t kStatusRegMap = 1U << 13U;
inline constexpr std::uint16_t kStatusCrcErr = 1U << 12U;
inline constexpr std::uint16_t kStatusReset = 1U << 10U;  // the device was reset
inline constexpr std::uint16_t kStatusDrdyMask = 0x000F;  // DRDY3..0: new data per channel

// MODE bits.
inline constexpr std::uint16_t kModeRegCrcEn = 1U << 13U;
inline constexpr std::uint16_t kModeRxCrcEn = 1U << 12U;
inline constexpr std::uint16_t kModeReset = 1U << 10U;   // write 0 to clear STATUS.RESET
inline constexpr std::uint16_t kModeWord24 = 1U << 8U;   // WLENGTH 01b
inline constexpr std::uint16_t kModeTimeout = 1U << 4U;  // SPI timeout enabled

inline constexpr std::int32_t kCodeMax = (1 << 23) - 1;
inline constexpr std::int32_t kCodeMin = -(1 << 23);
inline constexpr double kReferenceV = 1.2;

// CRC-16-CCITT as above over bytes, continuing from crc (0xFFFF to start).
[[nodiscard]] std::uint16_t crc16(std::span<const std::uint8_t> bytes,
                                  std::uint16_t crc = 0xFFFF) noexcept;

[[nodiscard]] constexpr std::uint16_t rreg(std::uint8_t address) noexcept {
  return static_cast<std::uint16_t>(0xA000U | ((address & 0x3FU) << 7U));
}
[[nodiscard]] constexpr std::uint16_t wreg(std::uint8_t address) noexcept {
  return static_cast<std::uint16_t>(0x6000U | ((address & 0x3FU) << 7U));
}
// The answer to a single-register WREG of that address.
[[nodiscard]] constexpr std::uint16_t wreg_answer(std::uint8_t address) noexcept {
  return static_cast<std::uint16_t>(0x4000U | ((address & 0x3FU) << 7U));
}

// CLOCK: all four channels on, oversampling ratio code (0: 128 .. 7: 16256), power mode
// (0: very low, 1: low, 2: high resolution).
[[nodiscard]] constexpr std::uint16_t clock_register(std::uint8_t osr_code,
                                                     std::uint8_t power) noexcept {
  return static_cast<std::uint16_t>(0x0F00U | ((osr_code & 7U) << 2U) | (power & 3U));
}
// The OSR of a code: 128 << code, except code 7 = 16256.
[[nodiscard]] constexpr int osr_of(std::uint8_t osr_code) noexcept {
  return osr_code >= 7 ? 16256 : 128 << osr_code;
}
// GAIN1: PGA gain code (gain = 2^code, code 0..7) of each channel.
[[nodiscard]] constexpr std::uint16_t gain_register(
    const std::array<std::uint8_t, 4>& codes) noexcept {
  return static_cast<std::uint16_t>(((codes[3] & 7U) << 12U) | ((codes[2] & 7U) << 8U) |
                                    ((codes[1] & 7U) << 4U) | (codes[0] & 7U));
}

// A host frame: the command, optional register data words, the input CRC word after them,
// zeros to the end. Returns the CRC written. data.size() <= kFrameWords - 2.
std::uint16_t encode_command(Frame& out, std::uint16_t command,
                             std::span<const std::uint16_t> data = {}) noexcept;

struct Reply {
  std::uint16_t response{0};                   // the previous command's answer (NULL: STATUS)
  std::array<std::int32_t, kChannels> code{};  // conversion codes, sign-extended
  std::uint16_t crc{0};                        // the CRC word received
  bool crc_ok{false};                          // it matches the CRC of the bytes before it
};
[[nodiscard]] Reply decode_reply(const Frame& in) noexcept;

// 16-bit item into / out of a 24-bit word at word index i.
void put_word16(Frame& f, std::size_t i, std::uint16_t v) noexcept;
[[nodiscard]] std::uint16_t word16(const Frame& f, std::size_t i) noexcept;
// 24-bit two's complement code into / out of word i.
void put_code(Frame& f, std::size_t i, std::int32_t code) noexcept;
[[nodiscard]] std::int32_t code(const Frame& f, std::size_t i) noexcept;

// Conversion code <-> input voltage [V] at a PGA gain.
[[nodiscard]] double volts(std::int32_t code, int gain) noexcept;
// The code the ADC gives for v (rounded, clipped to full scale).
[[nodiscard]] std::int32_t code_of(double v, int gain) noexcept;

}  // namespace selfsense::drivers::spi::ads131m04
