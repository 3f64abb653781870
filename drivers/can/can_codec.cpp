#include "selfsense/drivers/can/can_codec.hpp"

#include <array>
#include <cmath>
#include <cstdio>
#include <limits>

namespace selfsense::drivers::can {
namespace {

bool bit_at(std::span<const std::uint8_t> data, std::uint32_t p) noexcept {
  const unsigned byte = data[p / 8U];
  return ((byte >> (p % 8U)) & 1U) != 0U;
}

void set_bit(std::span<std::uint8_t> data, std::uint32_t p, bool on) noexcept {
  const unsigned mask = 1U << (p % 8U);
  const unsigned byte = data[p / 8U];
  data[p / 8U] = static_cast<std::uint8_t>(on ? (byte | mask) : (byte & ~mask));
}

std::uint64_t low_mask(std::uint32_t length) noexcept {
  return length >= 64U ? ~std::uint64_t{0} : (std::uint64_t{1} << length) - 1U;
}

}  // namespace

bool is_valid(const Signal& s, std::size_t max_bytes, std::string* why) {
  const auto fail = [why](const std::string& m) {
    if (why != nullptr) *why = m;
    return false;
  };
  if (s.length < 1 || s.length > 64) {
    return fail("length " + std::to_string(s.length) + " must be within [1, 64]");
  }
  const std::size_t bits = max_bytes * 8U;
  if (s.start_bit >= bits) {
    return fail("start_bit " + std::to_string(s.start_bit) + " must be < " + std::to_string(bits) +
                " (" + std::to_string(max_bytes) + " data bytes)");
  }
  if (s.order == ByteOrder::kLittle) {
    if (s.start_bit + s.length > bits) {
      return fail("start_bit " + std::to_string(s.start_bit) + " + length " +
                  std::to_string(s.length) + " runs past the frame's " + std::to_string(bits) +
                  " bits");
    }
  } else {
    // Motorola: the signal's bits climb bytes; the last byte used must exist.
    const std::uint32_t first_byte = s.start_bit / 8U;
    const std::uint32_t bits_in_first = s.start_bit % 8U + 1U;
    const std::uint32_t rest = s.length > bits_in_first ? s.length - bits_in_first : 0U;
    const std::uint32_t last_byte = first_byte + (rest + 7U) / 8U;
    if (last_byte >= max_bytes) {
      return fail("start_bit " + std::to_string(s.start_bit) + " with length " +
                  std::to_string(s.length) + " (big endian) needs byte " +
                  std::to_string(last_byte) + " of a frame of " + std::to_string(max_bytes) +
                  " bytes");
    }
  }
  if (!std::isfinite(s.scale) || s.scale == 0.0) return fail("scale must be finite and != 0");
  if (!std::isfinite(s.offset)) return fail("offset must be finite");
  return true;
}

bool is_valid(const FrameId& f, std::string* why) {
  const std::uint32_t max = f.extended ? kExtendedIdMax : kStandardIdMax;
  if (f.id > max) {
    if (why != nullptr) {
      std::array<char, 96> buf{};
      const int n =
          std::snprintf(buf.data(), buf.size(), "0x%X does not fit a %s identifier (max 0x%X)",
                        f.id, f.extended ? "29-bit extended" : "11-bit standard", max);
      *why = std::string(buf.data(), n > 0 ? static_cast<std::size_t>(n) : 0U);
    }
    return false;
  }
  return true;
}

std::size_t bytes_needed(const Signal& s) noexcept {
  std::uint32_t highest = 0;
  for_each_bit(s, [&highest](std::uint32_t p) {
    if (p > highest) highest = p;
  });
  return highest / 8U + 1U;
}

std::size_t fd_length(std::size_t bytes) noexcept {
  constexpr std::array<std::size_t, 7> kLengths{8, 12, 16, 20, 24, 32, 48};
  for (const std::size_t l : kLengths) {
    if (bytes <= l) return bytes <= 8 ? bytes : l;
  }
  return kFdMaxBytes;
}

std::uint64_t extract_raw(std::span<const std::uint8_t> data, const Signal& s) noexcept {
  std::uint64_t raw = 0;
  for_each_bit(s, [&](std::uint32_t p) { raw = (raw << 1U) | (bit_at(data, p) ? 1U : 0U); });
  return raw;
}

void insert_raw(std::span<std::uint8_t> data, const Signal& s, std::uint64_t raw) noexcept {
  std::uint32_t k = s.length;
  for_each_bit(s, [&](std::uint32_t p) {
    --k;
    set_bit(data, p, ((raw >> k) & 1U) != 0U);
  });
}

double decode(std::span<const std::uint8_t> data, const Signal& s) noexcept {
  if (s.length < 1 || s.length > 64) return 0.0;  // not a valid layout (is_valid() says so)
  const std::uint64_t raw = extract_raw(data, s);
  double value = 0.0;
  if (s.is_signed) {
    const std::uint64_t sign = std::uint64_t{1} << (s.length - 1U);
    const std::uint64_t extended = (raw & sign) != 0U ? (raw | ~low_mask(s.length)) : raw;
    value = static_cast<double>(static_cast<std::int64_t>(extended));
  } else {
    value = static_cast<double>(raw);
  }
  return value * s.scale + s.offset;
}

EncodeResult encode(std::span<std::uint8_t> data, const Signal& s, double value) noexcept {
  if (!std::isfinite(value)) return EncodeResult::kNotFinite;
  if (s.length < 1 || s.length > 64) return EncodeResult::kNotFinite;  // not a valid layout
  const double q = std::nearbyint((value - s.offset) / s.scale);
  if (!std::isfinite(q)) return EncodeResult::kNotFinite;
  EncodeResult result = EncodeResult::kOk;
  std::uint64_t raw = 0;
  if (s.is_signed) {
    // [-2^(L-1), 2^(L-1) - 1]; both ends are exact doubles (powers of two), compared before any
    // conversion so that none overflows.
    const double top = std::ldexp(1.0, static_cast<int>(s.length) - 1);
    std::int64_t v = 0;
    if (q >= top) {
      v = static_cast<std::int64_t>(low_mask(s.length - 1U));
      result = EncodeResult::kSaturated;
    } else if (q < -top) {
      v = s.length >= 64U ? std::numeric_limits<std::int64_t>::min()
                          : -static_cast<std::int64_t>(std::uint64_t{1} << (s.length - 1U));
      result = EncodeResult::kSaturated;
    } else {
      v = static_cast<std::int64_t>(q);
    }
    raw = static_cast<std::uint64_t>(v) & low_mask(s.length);
  } else {
    const double top = std::ldexp(1.0, static_cast<int>(s.length));
    if (q >= top) {
      raw = low_mask(s.length);
      result = EncodeResult::kSaturated;
    } else if (q < 0.0) {
      raw = 0;
      result = EncodeResult::kSaturated;
    } else {
      raw = static_cast<std::uint64_t>(q);
    }
  }
  insert_raw(data, s, raw);
  return result;
}

}  // namespace selfsense::drivers::can
