#include "selfsense/drivers/spi/ads131m04.hpp"

#include <cmath>

namespace selfsense::drivers::spi::ads131m04 {

std::uint16_t crc16(std::span<const std::uint8_t> bytes, std::uint16_t crc) noexcept {
  unsigned c = crc;  // unsigned arithmetic throughout (no promotion to int)
  for (const std::uint8_t b : bytes) {
    c ^= static_cast<unsigned>(b) << 8U;
    for (int bit = 0; bit < 8; ++bit)
      c = (c & 0x8000U) != 0U ? ((c << 1U) ^ 0x1021U) & 0xFFFFU : (c << 1U) & 0xFFFFU;
  }
  return static_cast<std::uint16_t>(c);
}

void put_word16(Frame& f, std::size_t i, std::uint16_t v) noexcept {
  const std::size_t at = i * kWordBytes;
  f.at(at) = static_cast<std::uint8_t>(v >> 8U);
  f.at(at + 1) = static_cast<std::uint8_t>(v & 0xFFU);
  f.at(at + 2) = 0;
}

std::uint16_t word16(const Frame& f, std::size_t i) noexcept {
  const std::size_t at = i * kWordBytes;
  return static_cast<std::uint16_t>((f.at(at) << 8U) | f.at(at + 1));
}

void put_code(Frame& f, std::size_t i, std::int32_t code) noexcept {
  const auto u = static_cast<std::uint32_t>(code) & 0xFFFFFFU;
  const std::size_t at = i * kWordBytes;
  f.at(at) = static_cast<std::uint8_t>(u >> 16U);
  f.at(at + 1) = static_cast<std::uint8_t>((u >> 8U) & 0xFFU);
  f.at(at + 2) = static_cast<std::uint8_t>(u & 0xFFU);
}

std::int32_t code(const Frame& f, std::size_t i) noexcept {
  const std::size_t at = i * kWordBytes;
  const std::uint32_t u = (static_cast<std::uint32_t>(f.at(at)) << 16U) |
                          (static_cast<std::uint32_t>(f.at(at + 1)) << 8U) | f.at(at + 2);
  // Sign extension of 24 bits.
  return (u & 0x800000U) != 0U ? static_cast<std::int32_t>(u) - (1 << 24)
                               : static_cast<std::int32_t>(u);
}

std::uint16_t encode_command(Frame& out, std::uint16_t command,
                             std::span<const std::uint16_t> data) noexcept {
  out.fill(0);
  put_word16(out, 0, command);
  std::size_t i = 1;
  for (const std::uint16_t d : data) {
    if (i + 1 >= kFrameWords) break;
    put_word16(out, i++, d);
  }
  const std::uint16_t crc = crc16(std::span<const std::uint8_t>(out.data(), i * kWordBytes));
  put_word16(out, i, crc);
  return crc;
}

Reply decode_reply(const Frame& in) noexcept {
  Reply r;
  r.response = word16(in, 0);
  for (std::size_t c = 0; c < kChannels; ++c)
    r.code.at(c) = code(in, 1 + c);
  r.crc = word16(in, kFrameWords - 1);
  const std::uint16_t expect =
      crc16(std::span<const std::uint8_t>(in.data(), (kFrameWords - 1) * kWordBytes));
  r.crc_ok = expect == r.crc && in.at(kFrameBytes - 1) == 0;
  return r;
}

double volts(std::int32_t code, int gain) noexcept {
  return static_cast<double>(code) * kReferenceV / (static_cast<double>(gain) * 8388608.0);
}

std::int32_t code_of(double v, int gain) noexcept {
  const double c = std::round(v * static_cast<double>(gain) / kReferenceV * 8388608.0);
  if (!(c > kCodeMin)) return kCodeMin;  // NaN too
  if (c > kCodeMax) return kCodeMax;
  return static_cast<std::int32_t>(c);
}

}  // namespace selfsense::drivers::spi::ads131m04
