// Fuzz target: decoding Modbus register values (include/selfsense/drivers/modbus/register_map.hpp),
// the words a device answers with, under register specs of every type and word order. Input: type,
// word order, scale, offset and range (from tables of realistic register scalings, or raw doubles
// when the first byte's top bit is set), a test value, then the words. Properties, for every spec
// that problem() accepts:
//  - decode() of any words: kOk means a finite value inside [min, max], kOutOfRange a finite
//    value outside it, kNotFinite a NaN or infinity;
//  - with a table scaling, a value decoded kOk encodes back (encode() true) to words that decode
//    to the same value; for integer types the words themselves come back;
//  - encode() of any value: true only for a value that decodes (finite) within half a raw step
//    (integers) or float32 rounding of it.
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "fuzz_check.hpp"
#include "selfsense/drivers/modbus/register_map.hpp"

namespace {

namespace mb = selfsense::drivers::modbus;
using selfsense::fuzz::require;

constexpr double kInf = std::numeric_limits<double>::infinity();
// NOLINTBEGIN(*-avoid-c-arrays): tables for ByteReader::pick
constexpr double kScales[] = {1.0, -1.0, 0.5, 0.001, 1e-6, 1e-9, 10.0, 1000.0, 2.5e5, 1.0 / 3.0};
constexpr double kOffsets[] = {0.0, 0.0, -100.0, 1000.0, 1e6, -3.5e-4, 0.25};
constexpr double kMins[] = {-kInf, -kInf, -1e6, 0.0, -1.0, -40000.0};
constexpr double kMaxs[] = {kInf, kInf, 1e6, 1.0, 2e9, 70000.0};
// NOLINTEND(*-avoid-c-arrays)

std::string describe(const mb::RegisterSpec& s, double value) {
  return std::string(mb::to_string(s.type)) + " " + std::string(mb::to_string(s.word_order)) +
         " scale " + std::to_string(s.scale) + " offset " + std::to_string(s.offset) + " value " +
         std::to_string(value);
}

void check_status(const mb::RegisterSpec& s, const mb::Decoded& d) {
  switch (d.status) {
    case mb::DecodeStatus::kOk:
      require(std::isfinite(d.value) && d.value >= s.min && d.value <= s.max,
              "kOk is a finite value inside [min, max]", describe(s, d.value));
      break;
    case mb::DecodeStatus::kOutOfRange:
      require(std::isfinite(d.value) && (d.value < s.min || d.value > s.max),
              "kOutOfRange is a finite value outside [min, max]", describe(s, d.value));
      break;
    case mb::DecodeStatus::kNotFinite:
      require(!std::isfinite(d.value), "kNotFinite is NaN or infinite", describe(s, d.value));
      break;
  }
}

}  // namespace

// NOLINTNEXTLINE(readability-identifier-naming): the name libFuzzer calls.
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  selfsense::fuzz::ByteReader in(data, size);
  const std::uint8_t flags = in.byte();
  const bool raw_scaling = (flags & 0x80U) != 0;
  mb::RegisterSpec spec;
  spec.enabled = true;
  spec.type = static_cast<mb::RegisterType>(flags & 3U);
  spec.word_order = static_cast<mb::WordOrder>((flags >> 2U) & 1U);
  if (raw_scaling) {
    spec.scale = std::bit_cast<double>(in.u64());
    spec.offset = std::bit_cast<double>(in.u64());
    spec.min = std::bit_cast<double>(in.u64());
    spec.max = std::bit_cast<double>(in.u64());
  } else {
    spec.scale = in.pick(kScales);
    spec.offset = in.pick(kOffsets);
    spec.min = in.pick(kMins);
    spec.max = in.pick(kMaxs);
  }
  if (!spec.problem().empty()) return 0;
  const double value = std::bit_cast<double>(in.u64());
  const std::array<std::uint16_t, 2> words{in.u16(), in.u16()};
  const auto n = static_cast<std::size_t>(mb::word_count(spec.type));
  const bool integer = spec.type != mb::RegisterType::kFloat32;

  // Any words a device sends.
  const mb::Decoded decoded = mb::decode(spec, std::span(words).first(n));
  check_status(spec, decoded);
  if (!raw_scaling && decoded.status == mb::DecodeStatus::kOk) {
    std::array<std::uint16_t, 2> again{};
    require(mb::encode(spec, decoded.value, std::span(again).first(n)), "a decoded value encodes",
            describe(spec, decoded.value));
    const mb::Decoded back = mb::decode(spec, std::span(again).first(n));
    require(back.value == decoded.value, "decode(encode(decode(words))) == decode(words)",
            describe(spec, decoded.value) + " -> " + std::to_string(back.value));
    if (integer) {
      require(
          std::equal(words.begin(), words.begin() + static_cast<std::ptrdiff_t>(n), again.begin()),
          "integer registers come back unchanged", describe(spec, decoded.value));
    }
  }

  // Any value the loop commands.
  std::array<std::uint16_t, 2> encoded{};
  if (mb::encode(spec, value, std::span(encoded).first(n))) {
    require(std::isfinite(value), "only finite values encode", describe(spec, value));
    const mb::Decoded back = mb::decode(spec, std::span(encoded).first(n));
    require(std::isfinite(back.value), "an encoded value decodes finite", describe(spec, value));
    const double raw = (value - spec.offset) / spec.scale;
    const double step = integer ? 0.5 : std::abs(raw) * 0x1p-24 + 0x1p-149;
    // Rounding of the scaling itself, a few ulps of the larger of value and offset.
    const double slack = 8.0 * std::numeric_limits<double>::epsilon() *
                         (std::abs(value) + std::abs(spec.offset) + std::abs(back.value));
    require(std::abs(back.value - value) <= step * std::abs(spec.scale) + slack,
            "an encoded value decodes within rounding",
            describe(spec, value) + " -> " + std::to_string(back.value));
  }
  return 0;
}
