// The ADS131M04 and DAC8563 protocols (include/selfsense/drivers/spi/ads131m04.hpp, dac8563.hpp):
// the CRC against its catalogued check value and an independent bit-serial reference, command words
// against the data sheet's bit patterns, frames, codes and scaling at full scale and one LSB.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <limits>
#include <random>
#include <string_view>
#include <vector>

#include "selfsense/drivers/spi/ads131m04.hpp"
#include "selfsense/drivers/spi/dac8563.hpp"

namespace {

namespace adc = selfsense::drivers::spi::ads131m04;
namespace dac = selfsense::drivers::spi::dac8563;

// CRC-16-CCITT as polynomial division of the message followed by 16 zero bits, bit by bit,
// after XOR-ing the initial value into the first two bytes: a different formulation from the
// driver's, so a shared mistake is unlikely.
std::uint16_t reference_crc(std::vector<std::uint8_t> m) {
  if (m.size() < 2) m.resize(2, 0);  // not used for shorter messages below
  m[0] ^= 0xFF;
  m[1] ^= 0xFF;
  m.push_back(0);
  m.push_back(0);
  std::uint32_t reg = 0;
  for (const std::uint8_t byte : m) {
    for (int bit = 7; bit >= 0; --bit) {
      reg = (reg << 1U) | ((byte >> bit) & 1U);
      if ((reg & 0x10000U) != 0U) reg ^= 0x11021U;
    }
  }
  return static_cast<std::uint16_t>(reg);
}

TEST(Ads131m04Crc, CatalogueCheckValue) {
  // CRC-16/CCITT-FALSE (poly 1021h, init FFFFh, no reflection, no final XOR), the data sheet's
  // CRC_TYPE 0: the catalogued check value of "123456789" is 29B1h.
  constexpr std::string_view kCheck = "123456789";
  const std::vector<std::uint8_t> bytes(kCheck.begin(), kCheck.end());
  EXPECT_EQ(adc::crc16(bytes), 0x29B1);
  EXPECT_EQ(reference_crc(bytes), 0x29B1);
  EXPECT_EQ(adc::crc16(std::vector<std::uint8_t>{}), 0xFFFF);  // nothing: the seed
}

TEST(Ads131m04Crc, MatchesTheBitSerialReferenceOnRandomFrames) {
  std::mt19937 rng(3);
  for (int i = 0; i < 500; ++i) {
    std::vector<std::uint8_t> m(2 + static_cast<std::size_t>(rng() % 30));
    for (auto& b : m)
      b = static_cast<std::uint8_t>(rng());
    ASSERT_EQ(adc::crc16(m), reference_crc(m)) << i;
  }
}

TEST(Ads131m04Crc, AFrameEndingInItsCrcChecksToZero) {
  // A property of this CRC: running it over the message followed by its own CRC gives 0.
  adc::Frame f{};
  adc::put_word16(f, 0, 0x0500);
  adc::put_code(f, 1, 123456);
  adc::put_code(f, 2, -7);
  const std::uint16_t crc = adc::crc16(std::span<const std::uint8_t>(f.data(), 15));
  const std::array<std::uint8_t, 17> with{f[0],
                                          f[1],
                                          f[2],
                                          f[3],
                                          f[4],
                                          f[5],
                                          f[6],
                                          f[7],
                                          f[8],
                                          f[9],
                                          f[10],
                                          f[11],
                                          f[12],
                                          f[13],
                                          f[14],
                                          static_cast<std::uint8_t>(crc >> 8U),
                                          static_cast<std::uint8_t>(crc & 0xFFU)};
  EXPECT_EQ(adc::crc16(with), 0);
}

TEST(Ads131m04Commands, BitPatternsOfTheDataSheet) {
  // RREG 101a aaaa annn nnnn and WREG 011a aaaa annn nnnn with n = registers - 1 = 0.
  EXPECT_EQ(adc::rreg(0x00), 0xA000);  // ID
  EXPECT_EQ(adc::rreg(0x02), 0xA100);  // MODE: a = 000010 -> bits 12..7
  EXPECT_EQ(adc::rreg(0x3F), 0xBF80);
  EXPECT_EQ(adc::wreg(0x03), 0x6180);         // CLOCK
  EXPECT_EQ(adc::wreg(0x04), 0x6200);         // GAIN1
  EXPECT_EQ(adc::wreg_answer(0x03), 0x4180);  // 010a aaaa ammm mmmm
  EXPECT_EQ(adc::kReset, 0x0011);
  EXPECT_EQ(adc::kStandby, 0x0022);
  EXPECT_EQ(adc::kWakeup, 0x0033);
  // CLOCK reset value 0F0Eh: channels on, OSR code 3 (1024), high resolution.
  EXPECT_EQ(adc::clock_register(3, 2), adc::kClockResetValue);
  EXPECT_EQ(adc::osr_of(0), 128);
  EXPECT_EQ(adc::osr_of(3), 1024);
  EXPECT_EQ(adc::osr_of(7), 16256);
  EXPECT_EQ(adc::gain_register({1, 2, 0, 7}), 0x7021);
}

TEST(Ads131m04Frames, CommandFrameCarriesItsDataAndInputCrc) {
  adc::Frame f{};
  const std::array<std::uint16_t, 1> data{0x1234};
  const std::uint16_t crc = adc::encode_command(f, adc::wreg(0x02), data);
  // Words: 6100h 00, 1234h 00, CRC 00, zeros.
  EXPECT_EQ(f[0], 0x61);
  EXPECT_EQ(f[1], 0x00);
  EXPECT_EQ(f[2], 0x00);
  EXPECT_EQ(f[3], 0x12);
  EXPECT_EQ(f[4], 0x34);
  EXPECT_EQ(f[5], 0x00);
  EXPECT_EQ(crc, reference_crc({0x61, 0x00, 0x00, 0x12, 0x34, 0x00}));
  EXPECT_EQ(adc::word16(f, 2), crc);
  for (std::size_t i = 9; i < f.size(); ++i)
    EXPECT_EQ(f.at(i), 0) << i;
  // NULL: the CRC of 00 00 00 follows at once.
  adc::encode_command(f, adc::kNull);
  EXPECT_EQ(adc::word16(f, 1), reference_crc({0, 0, 0}));
}

TEST(Ads131m04Frames, ReplyDecodesCodesAndRejectsACorruptedBit) {
  adc::Frame f{};
  adc::put_word16(f, 0, 0x050F);
  adc::put_code(f, 1, adc::kCodeMax);
  adc::put_code(f, 2, adc::kCodeMin);
  adc::put_code(f, 3, -1);
  adc::put_code(f, 4, 1);
  adc::put_word16(f, 5, adc::crc16(std::span<const std::uint8_t>(f.data(), 15)));
  EXPECT_EQ(f[3], 0x7F);  // +full scale 7FFFFFh
  EXPECT_EQ(f[6], 0x80);  // -full scale 800000h
  EXPECT_EQ(f[9], 0xFF);  // -1: FFFFFFh
  adc::Reply r = adc::decode_reply(f);
  EXPECT_TRUE(r.crc_ok);
  EXPECT_EQ(r.response, 0x050F);
  EXPECT_EQ(r.code[0], 8388607);
  EXPECT_EQ(r.code[1], -8388608);
  EXPECT_EQ(r.code[2], -1);
  EXPECT_EQ(r.code[3], 1);
  for (std::size_t byte = 0; byte < 15; ++byte) {
    adc::Frame bad = f;
    bad.at(byte) ^= 0x10;
    EXPECT_FALSE(adc::decode_reply(bad).crc_ok) << byte;
  }
}

TEST(Ads131m04Codes, FullScaleAndOneLsb) {
  // +-1.2 V / gain over 24 bits: 1 LSB = 2.4 V / 2^24 = 143.05 nV at gain 1.
  EXPECT_NEAR(adc::volts(1, 1), 1.2 / 8388608.0, 1e-15);
  EXPECT_NEAR(adc::volts(adc::kCodeMin, 1), -1.2, 1e-12);
  EXPECT_NEAR(adc::volts(adc::kCodeMax, 4), 0.3, 1e-6);
  EXPECT_EQ(adc::code_of(0.6, 1), 4194304);
  EXPECT_EQ(adc::code_of(0.6, 2), adc::kCodeMax);  // beyond 0.6 V full scale: clipped
  EXPECT_EQ(adc::code_of(-5.0, 1), adc::kCodeMin);
  for (const double v : {-1.1, -0.3, 0.0, 1e-6, 0.77}) {
    EXPECT_NEAR(adc::volts(adc::code_of(v, 1), 1), v, 1.2 / 8388608.0);
  }
}

TEST(Dac8563Frames, CommandAddressDataBits) {
  // DB21..19 command, DB18..16 address, DB15..0 data.
  const dac::Frame f = dac::frame(dac::Command::kWriteUpdate, dac::kDacA, 0xABCD);
  EXPECT_EQ(f[0], 0x18);  // 00 011 000
  EXPECT_EQ(f[1], 0xAB);
  EXPECT_EQ(f[2], 0xCD);
  EXPECT_EQ(dac::frame(dac::Command::kReset, 0, 1)[0], 0x28);           // 101 000: 280001h
  EXPECT_EQ(dac::frame(dac::Command::kReference, 0, 1)[0], 0x38);       // 111 000: 380001h
  EXPECT_EQ(dac::frame(dac::Command::kPower, dac::kBoth, 3)[0], 0x27);  // 100 111: 270003h
  const dac::Decoded d = dac::decode(dac::frame(dac::Command::kWriteInput, dac::kDacB, 7));
  EXPECT_EQ(d.command, dac::Command::kWriteInput);
  EXPECT_EQ(d.address, dac::kDacB);
  EXPECT_EQ(d.data, 7);
}

TEST(Dac8563Codes, StraightBinaryClipped) {
  EXPECT_EQ(dac::code_of(2.5, 5.0).code, 32768);
  EXPECT_FALSE(dac::code_of(2.5, 5.0).clipped);
  EXPECT_EQ(dac::code_of(5.0, 5.0).code, 65535);
  EXPECT_TRUE(dac::code_of(5.0, 5.0).clipped);
  EXPECT_EQ(dac::code_of(-0.1, 5.0).code, 0);
  EXPECT_TRUE(dac::code_of(-0.1, 5.0).clipped);
  EXPECT_TRUE(dac::code_of(std::numeric_limits<double>::quiet_NaN(), 5.0).clipped);
  EXPECT_NEAR(dac::volts(dac::code_of(1.234, 5.0).code, 5.0), 1.234, 5.0 / 65536.0);
}

}  // namespace
