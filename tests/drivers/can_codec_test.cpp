// The CAN signal codec against hand-worked bytes (Intel and Motorola layouts as a DBC file gives
// them), against an independent reference (the 8 data bytes as one 64-bit word), and at its
// limits (sign, saturation, 64-bit signals, neighbouring bits left alone).
#include "selfsense/drivers/can/can_codec.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>

namespace {

using selfsense::drivers::can::ByteOrder;
using selfsense::drivers::can::bytes_needed;
using selfsense::drivers::can::decode;
using selfsense::drivers::can::encode;
using selfsense::drivers::can::EncodeResult;
using selfsense::drivers::can::extract_raw;
using selfsense::drivers::can::fd_length;
using selfsense::drivers::can::FrameId;
using selfsense::drivers::can::insert_raw;
using selfsense::drivers::can::is_valid;
using selfsense::drivers::can::Signal;
using Bytes = std::array<std::uint8_t, 8>;

Signal sig(std::uint32_t start, std::uint32_t length, ByteOrder order, bool is_signed = false,
           double scale = 1.0, double offset = 0.0) {
  return Signal{start, length, order, is_signed, scale, offset};
}

TEST(CanCodec, IntelByteAligned16Bit) {
  Bytes b{};
  insert_raw(b, sig(8, 16, ByteOrder::kLittle), 0x1234);
  EXPECT_EQ(b, (Bytes{0x00, 0x34, 0x12, 0, 0, 0, 0, 0}));
  EXPECT_EQ(extract_raw(b, sig(8, 16, ByteOrder::kLittle)), 0x1234U);
}

TEST(CanCodec, MotorolaByteAligned16Bit) {
  // DBC start bit of a big-endian signal is its MSB: byte 0, bit 7 -> 7.
  Bytes b{};
  insert_raw(b, sig(7, 16, ByteOrder::kBig), 0x1234);
  EXPECT_EQ(b, (Bytes{0x12, 0x34, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(extract_raw(b, sig(7, 16, ByteOrder::kBig)), 0x1234U);
  Bytes c{};
  insert_raw(c, sig(23, 16, ByteOrder::kBig), 0xBEEF);  // bytes 2..3
  EXPECT_EQ(c, (Bytes{0, 0, 0xBE, 0xEF, 0, 0, 0, 0}));
}

TEST(CanCodec, IntelUnalignedTwelveBits) {
  // 12 bits from bit 4: the low nibble of the value in byte 0's high nibble, the rest in byte 1.
  Bytes b{};
  insert_raw(b, sig(4, 12, ByteOrder::kLittle), 0xABC);
  EXPECT_EQ(b, (Bytes{0xC0, 0xAB, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(extract_raw(b, sig(4, 12, ByteOrder::kLittle)), 0xABCU);
}

TEST(CanCodec, MotorolaUnalignedTwelveBits) {
  // MSB at byte 0 bit 3: the value's top nibble in byte 0's low nibble, the low byte in byte 1.
  Bytes b{};
  insert_raw(b, sig(3, 12, ByteOrder::kBig), 0xABC);
  EXPECT_EQ(b, (Bytes{0x0A, 0xBC, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(extract_raw(b, sig(3, 12, ByteOrder::kBig)), 0xABCU);
  EXPECT_EQ(bytes_needed(sig(3, 12, ByteOrder::kBig)), 2U);
}

TEST(CanCodec, InsertLeavesOtherBitsAlone) {
  Bytes b{};
  b.fill(0xFF);
  insert_raw(b, sig(4, 12, ByteOrder::kLittle), 0);
  EXPECT_EQ(b, (Bytes{0x0F, 0x00, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF}));
  b.fill(0xFF);
  insert_raw(b, sig(3, 12, ByteOrder::kBig), 0);
  EXPECT_EQ(b, (Bytes{0xF0, 0x00, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF}));
}

TEST(CanCodec, SignedValuesAreSignExtended) {
  Bytes b{};
  insert_raw(b, sig(0, 16, ByteOrder::kLittle), 0xFFFF);
  EXPECT_EQ(decode(b, sig(0, 16, ByteOrder::kLittle, true)), -1.0);
  EXPECT_EQ(decode(b, sig(0, 16, ByteOrder::kLittle, false)), 65535.0);
  Bytes c{};
  insert_raw(c, sig(7, 4, ByteOrder::kBig), 0x8);  // 4-bit two's complement: -8
  EXPECT_EQ(decode(c, sig(7, 4, ByteOrder::kBig, true)), -8.0);
  EXPECT_EQ(decode(c, sig(7, 4, ByteOrder::kBig, false)), 8.0);
}

TEST(CanCodec, ScaleAndOffset) {
  const Signal s = sig(0, 16, ByteOrder::kLittle, true, 0.5, -100.0);
  Bytes b{};
  EXPECT_EQ(encode(b, s, -100.0), EncodeResult::kOk);
  EXPECT_EQ(extract_raw(b, s), 0U);
  EXPECT_EQ(encode(b, s, 0.0), EncodeResult::kOk);  // raw 200
  EXPECT_EQ(b[0], 200);
  EXPECT_EQ(decode(b, s), 0.0);
  EXPECT_EQ(encode(b, s, -200.25), EncodeResult::kOk);  // raw -200.5 -> -200 (to even)
  EXPECT_EQ(decode(b, s), -200.0);
}

TEST(CanCodec, PhysicalRoundTripWithinHalfAStep) {
  const Signal e = sig(0, 32, ByteOrder::kLittle, true, 1.0, 0.0);  // V/m
  const Signal d = sig(39, 32, ByteOrder::kBig, true, 1e-9, 0.0);   // C/m^2
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> field(-2e6, 2e6);
  std::uniform_real_distribution<double> charge(-0.05, 0.05);
  for (int i = 0; i < 1000; ++i) {
    Bytes b{};
    const double ev = field(rng);
    const double dv = charge(rng);
    ASSERT_EQ(encode(b, e, ev), EncodeResult::kOk);
    ASSERT_EQ(encode(b, d, dv), EncodeResult::kOk);
    EXPECT_NEAR(decode(b, e), ev, 0.5);
    EXPECT_NEAR(decode(b, d), dv, 0.5e-9 + 1e-15);
  }
}

TEST(CanCodec, SaturatesAtTheRawRange) {
  Bytes b{};
  const Signal u8 = sig(0, 8, ByteOrder::kLittle);
  EXPECT_EQ(encode(b, u8, 256.0), EncodeResult::kSaturated);
  EXPECT_EQ(b[0], 255);
  EXPECT_EQ(encode(b, u8, -1.0), EncodeResult::kSaturated);
  EXPECT_EQ(b[0], 0);
  EXPECT_EQ(encode(b, u8, 255.4), EncodeResult::kOk);
  EXPECT_EQ(b[0], 255);
  const Signal s8 = sig(0, 8, ByteOrder::kLittle, true);
  EXPECT_EQ(encode(b, s8, 128.0), EncodeResult::kSaturated);
  EXPECT_EQ(decode(b, s8), 127.0);
  EXPECT_EQ(encode(b, s8, -129.0), EncodeResult::kSaturated);
  EXPECT_EQ(decode(b, s8), -128.0);
  EXPECT_EQ(encode(b, s8, -128.0), EncodeResult::kOk);
}

TEST(CanCodec, NotFiniteWritesNothing) {
  Bytes b{};
  b.fill(0x5A);
  const Signal s = sig(0, 16, ByteOrder::kLittle, true);
  EXPECT_EQ(encode(b, s, std::numeric_limits<double>::quiet_NaN()), EncodeResult::kNotFinite);
  EXPECT_EQ(encode(b, s, std::numeric_limits<double>::infinity()), EncodeResult::kNotFinite);
  EXPECT_EQ(b[0], 0x5A);
  EXPECT_EQ(b[1], 0x5A);
}

TEST(CanCodec, SixtyFourBitSignals) {
  for (const ByteOrder order : {ByteOrder::kLittle, ByteOrder::kBig}) {
    const Signal s = sig(order == ByteOrder::kLittle ? 0 : 7, 64, order, true);
    Bytes b{};
    EXPECT_EQ(encode(b, s, -1.0), EncodeResult::kOk);
    EXPECT_EQ(b, (Bytes{0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF}));
    EXPECT_EQ(encode(b, s, 1e30), EncodeResult::kSaturated);
    EXPECT_EQ(extract_raw(b, s), 0x7FFFFFFFFFFFFFFFULL);
    EXPECT_EQ(encode(b, s, -1e30), EncodeResult::kSaturated);
    EXPECT_EQ(extract_raw(b, s), 0x8000000000000000ULL);
    const Signal u = sig(s.start_bit, 64, order, false);
    EXPECT_EQ(encode(b, u, 1e30), EncodeResult::kSaturated);
    EXPECT_EQ(extract_raw(b, u), ~0ULL);
  }
  Bytes b{};
  insert_raw(b, sig(7, 64, ByteOrder::kBig), 0x0102030405060708ULL);
  EXPECT_EQ(b, (Bytes{1, 2, 3, 4, 5, 6, 7, 8}));
  insert_raw(b, sig(0, 64, ByteOrder::kLittle), 0x0102030405060708ULL);
  EXPECT_EQ(b, (Bytes{8, 7, 6, 5, 4, 3, 2, 1}));
}

// Reference: the 8 bytes as one word. Intel: little-endian load, shift by the start bit.
// Motorola: big-endian load; the DBC position 8*byte + bit is word bit 8*(7-byte) + bit, the
// signal's LSB sits length-1 word bits below its MSB.
std::uint64_t reference_extract(const Bytes& b, const Signal& s) {
  std::uint64_t word = 0;
  const std::uint64_t mask = s.length == 64 ? ~0ULL : (1ULL << s.length) - 1;
  if (s.order == ByteOrder::kLittle) {
    for (int i = 7; i >= 0; --i)
      word = (word << 8U) | b[static_cast<std::size_t>(i)];
    return (word >> s.start_bit) & mask;
  }
  for (std::size_t i = 0; i < 8; ++i)
    word = (word << 8U) | b[i];
  const std::uint32_t msb = 8 * (7 - s.start_bit / 8) + s.start_bit % 8;
  return (word >> (msb + 1 - s.length)) & mask;
}

TEST(CanCodec, EveryLayoutOfEightBytesMatchesTheReference) {
  std::mt19937_64 rng(11);
  int layouts = 0;
  for (const ByteOrder order : {ByteOrder::kLittle, ByteOrder::kBig}) {
    for (std::uint32_t start = 0; start < 64; ++start) {
      for (std::uint32_t length = 1; length <= 64; ++length) {
        const Signal s = sig(start, length, order);
        if (!is_valid(s, 8, nullptr)) continue;
        ++layouts;
        Bytes b{};
        for (auto& x : b)
          x = static_cast<std::uint8_t>(rng());
        const Bytes before = b;
        ASSERT_EQ(extract_raw(b, s), reference_extract(b, s))
            << "start " << start << " length " << length;
        const std::uint64_t v = rng() & (length == 64 ? ~0ULL : (1ULL << length) - 1);
        insert_raw(b, s, v);
        ASSERT_EQ(reference_extract(b, s), v) << "start " << start << " length " << length;
        // Every bit outside the signal is unchanged.
        Bytes outside_before = before;
        Bytes outside_after = b;
        insert_raw(outside_before, s, 0);
        insert_raw(outside_after, s, 0);
        ASSERT_EQ(outside_before, outside_after);
        ASSERT_LE(bytes_needed(s), 8U);
      }
    }
  }
  // Intel: sum over start of (64 - start) lengths; Motorola has as many (mirrored).
  EXPECT_EQ(layouts, 2 * 64 * 65 / 2);
}

TEST(CanCodec, ValidationNamesTheProblem) {
  std::string why;
  EXPECT_FALSE(is_valid(sig(0, 0, ByteOrder::kLittle), 8, &why));
  EXPECT_EQ(why, "length 0 must be within [1, 64]");
  EXPECT_FALSE(is_valid(sig(60, 8, ByteOrder::kLittle), 8, &why));
  EXPECT_EQ(why, "start_bit 60 + length 8 runs past the frame's 64 bits");
  EXPECT_TRUE(is_valid(sig(60, 8, ByteOrder::kLittle), 64, &why));
  EXPECT_FALSE(is_valid(sig(64, 8, ByteOrder::kLittle), 8, &why));
  EXPECT_EQ(why, "start_bit 64 must be < 64 (8 data bytes)");
  EXPECT_FALSE(is_valid(sig(59, 16, ByteOrder::kBig), 8, &why));
  EXPECT_EQ(why, "start_bit 59 with length 16 (big endian) needs byte 9 of a frame of 8 bytes");
  EXPECT_TRUE(is_valid(sig(63, 8, ByteOrder::kBig), 8, &why));
  EXPECT_FALSE(is_valid(sig(0, 8, ByteOrder::kLittle, false, 0.0), 8, &why));
  EXPECT_EQ(why, "scale must be finite and != 0");
  EXPECT_FALSE(is_valid(FrameId{0x800, false}, &why));
  EXPECT_EQ(why, "0x800 does not fit a 11-bit standard identifier (max 0x7FF)");
  EXPECT_TRUE(is_valid(FrameId{0x800, true}, &why));
  EXPECT_FALSE(is_valid(FrameId{0x20000000, true}, &why));
}

TEST(CanCodec, FdLengths) {
  EXPECT_EQ(fd_length(0), 0U);
  EXPECT_EQ(fd_length(8), 8U);
  EXPECT_EQ(fd_length(9), 12U);
  EXPECT_EQ(fd_length(13), 16U);
  EXPECT_EQ(fd_length(33), 48U);
  EXPECT_EQ(fd_length(49), 64U);
  EXPECT_EQ(fd_length(64), 64U);
}

TEST(CanCodec, SignalsInFdFrames) {
  std::array<std::uint8_t, 64> b{};
  const Signal s = sig(8 * 60 + 7, 32, ByteOrder::kBig, true, 0.25);
  ASSERT_TRUE(is_valid(s, 64, nullptr));
  EXPECT_FALSE(is_valid(s, 8, nullptr));
  EXPECT_EQ(bytes_needed(s), 64U);
  EXPECT_EQ(encode(b, s, -3.75), EncodeResult::kOk);
  EXPECT_EQ(b[60], 0xFF);
  EXPECT_EQ(b[63], 0xF1);  // -15
  EXPECT_EQ(decode(b, s), -3.75);
}

}  // namespace
