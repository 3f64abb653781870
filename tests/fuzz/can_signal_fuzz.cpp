// Fuzz target: CAN signal decoding (include/selfsense/drivers/can/can_codec.hpp) of any frame data
// under any signal layout (start bit, length, byte order, signedness, scale, offset; classic or
// FD). Input: the layout (scale and offset from a table, or raw doubles when the first byte's top
// bit is set), then the frame's data bytes.
// Properties, for every layout is_valid() accepts:
//  - the signal's bits are `length` distinct bits inside bytes_needed() <= the frame's bytes;
//  - extract_raw() fits in `length` bits; insert_raw() of it changes nothing; insert_raw() of
//    all ones or all zeros changes exactly the signal's bits;
//  - decode() is raw (two's complement when signed) * scale + offset, computed independently
//    (lengths up to 53 bits, where doubles hold every raw exactly);
//  - with a table scaling and up to 32 bits, encode(decode(data)) is kOk and writes the same
//    raw bits back;
//  - fd_length() of the bytes needed is a CAN FD length that holds them.
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <string>

#include "fuzz_check.hpp"
#include "selfsense/drivers/can/can_codec.hpp"

namespace {

namespace can = selfsense::drivers::can;
using selfsense::fuzz::require;

// NOLINTBEGIN(*-avoid-c-arrays): tables for ByteReader::pick
constexpr double kScales[] = {1.0, 0.1, 0.01, -1.0, 0.5, 1e-6, 1e-9, 3.0, 1000.0, 0.0625};
constexpr double kOffsets[] = {0.0, 0.0, -40.0, 1000.0, -1e-3, 0.5};
// NOLINTEND(*-avoid-c-arrays)

std::string describe(const can::Signal& s) {
  return "start_bit " + std::to_string(s.start_bit) + " length " + std::to_string(s.length) +
         (s.order == can::ByteOrder::kBig ? " big" : " little") +
         (s.is_signed ? " signed" : " unsigned") + " scale " + std::to_string(s.scale) +
         " offset " + std::to_string(s.offset);
}

std::uint64_t low_mask(std::uint32_t length) {
  return length >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << length) - 1U;
}

int changed_bits(const std::array<std::uint8_t, can::kFdMaxBytes>& a,
                 const std::array<std::uint8_t, can::kFdMaxBytes>& b) {
  int n = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    n += std::popcount(static_cast<unsigned>(a.at(i) ^ b.at(i)));
  return n;
}

void check_bits(const can::Signal& s, std::size_t max_bytes) {
  const std::size_t needed = can::bytes_needed(s);
  require(needed >= 1 && needed <= max_bytes, "bytes_needed fits the frame", describe(s));
  std::array<bool, can::kFdMaxBytes * 8> seen{};
  std::uint32_t count = 0;
  bool inside = true;
  bool distinct = true;
  can::for_each_bit(s, [&](std::uint32_t p) {
    ++count;
    if (p >= needed * 8) {
      inside = false;
      return;
    }
    distinct = distinct && !seen.at(p);
    seen.at(p) = true;
  });
  require(count == s.length, "a signal has `length` bits", describe(s));
  require(inside, "a signal's bits lie inside bytes_needed()", describe(s));
  require(distinct, "a signal's bits are distinct", describe(s));
  const std::size_t fd = can::fd_length(needed);
  require(fd >= needed && fd <= can::kFdMaxBytes, "fd_length holds the bytes", describe(s));
}

}  // namespace

// NOLINTNEXTLINE(readability-identifier-naming): the name libFuzzer calls.
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  selfsense::fuzz::ByteReader in(data, size);
  const std::uint8_t flags = in.byte();
  const bool raw_scaling = (flags & 0x80U) != 0;
  const std::size_t max_bytes = (flags & 1U) != 0 ? can::kFdMaxBytes : can::kClassicMaxBytes;
  can::Signal s;
  s.order = (flags & 2U) != 0 ? can::ByteOrder::kBig : can::ByteOrder::kLittle;
  s.is_signed = (flags & 4U) != 0;
  s.start_bit = in.u16() % 600U;
  s.length = in.byte() % 70U;
  if (raw_scaling) {
    s.scale = std::bit_cast<double>(in.u64());
    s.offset = std::bit_cast<double>(in.u64());
  } else {
    s.scale = in.pick(kScales);
    s.offset = in.pick(kOffsets);
  }
  std::string why;
  if (!can::is_valid(s, max_bytes, &why)) {
    require(!why.empty(), "a rejected layout says why", describe(s));
    return 0;
  }
  check_bits(s, max_bytes);

  std::array<std::uint8_t, can::kFdMaxBytes> frame{};
  const auto rest = in.rest();
  std::copy_n(rest.begin(), std::min(rest.size(), max_bytes), frame.begin());
  const std::uint64_t raw = can::extract_raw(frame, s);
  require((raw & ~low_mask(s.length)) == 0, "extract_raw fits in `length` bits", describe(s));

  auto copy = frame;
  can::insert_raw(copy, s, raw);
  require(copy == frame, "insert_raw of the extracted bits changes nothing", describe(s));
  auto ones = frame;
  can::insert_raw(ones, s, ~std::uint64_t{0});
  auto zeros = frame;
  can::insert_raw(zeros, s, 0);
  require(changed_bits(ones, zeros) == static_cast<int>(s.length),
          "insert_raw changes exactly the signal's bits", describe(s));
  require(can::extract_raw(ones, s) == low_mask(s.length) && can::extract_raw(zeros, s) == 0,
          "insert_raw then extract_raw gives the bits back", describe(s));

  const double value = can::decode(frame, s);
  if (s.length <= 53) {
    double expected = static_cast<double>(raw);
    if (s.is_signed && ((raw >> (s.length - 1U)) & 1U) != 0U) {
      expected -= std::ldexp(1.0, static_cast<int>(s.length));
    }
    expected = expected * s.scale + s.offset;
    require(value == expected || (std::isnan(value) && std::isnan(expected)),
            "decode is raw * scale + offset", describe(s));
  }
  if (!raw_scaling && s.length <= 32) {
    auto back = frame;
    can::insert_raw(back, s, ~raw);
    require(can::encode(back, s, value) == can::EncodeResult::kOk, "a decoded value encodes",
            describe(s));
    require(can::extract_raw(back, s) == raw, "encode(decode(raw)) writes raw", describe(s));
  }
  return 0;
}
