// The CAN signal codec: one signal of a frame's data bytes, packed and unpacked the way a DBC file
// describes it (start bit, length, byte order, signedness, scale and offset). Pure: no sockets,
// no Linux headers, usable on any host; the SocketCAN driver (can_driver.hpp) and the simulated
// CAN node (`selfsense sim-device --can`) both use it.
//
// Bit numbering (as in DBC files): bit i of byte b is frame bit 8*b + i, bit 0 the least
// significant bit of the byte.
//  - little endian (Intel): start_bit is the signal's least significant bit; the signal's bit k
//    is frame bit start_bit + k (it climbs into the following bytes).
//  - big endian (Motorola): start_bit is the signal's most significant bit; going towards the
//    least significant bit, the position falls within a byte and continues at bit 7 of the next
//    byte. A byte-aligned 16-bit big-endian signal in bytes 2..3 has start_bit 8*2 + 7 = 23.
// The physical value is raw * scale + offset; raw is an unsigned or two's-complement integer of
// `length` bits (1..64).
//
// decode(), encode(), extract_raw() and insert_raw() are real-time safe: noexcept, no
// allocation, a loop of at most 64 steps.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace selfsense::drivers::can {

inline constexpr std::size_t kClassicMaxBytes = 8;
inline constexpr std::size_t kFdMaxBytes = 64;
inline constexpr std::uint32_t kStandardIdMax = 0x7FFU;
inline constexpr std::uint32_t kExtendedIdMax = 0x1FFFFFFFU;

enum class ByteOrder : std::uint8_t { kLittle, kBig };

struct Signal {
  std::uint32_t start_bit{0};  // see the numbering above
  std::uint32_t length{8};     // bits, 1..64
  ByteOrder order{ByteOrder::kLittle};
  bool is_signed{false};
  double scale{1.0};  // physical per raw unit, finite and != 0
  double offset{0.0};
};

// A frame's identity: the 11-bit (standard) or 29-bit (extended) identifier.
struct FrameId {
  std::uint32_t id{0};
  bool extended{false};
  friend bool operator==(const FrameId&, const FrameId&) = default;
};

// True when the layout is possible in a frame of max_bytes data bytes; otherwise false and *why
// says what is wrong ("length 0 must be within [1, 64]"). Not real-time (builds a message).
[[nodiscard]] bool is_valid(const Signal& s, std::size_t max_bytes, std::string* why);
[[nodiscard]] bool is_valid(const FrameId& f, std::string* why);

// Bytes a frame needs to carry the signal (its highest byte + 1). The layout must be valid.
[[nodiscard]] std::size_t bytes_needed(const Signal& s) noexcept;
// Calls f(frame_bit) for every frame bit of the signal, most significant first.
template <typename F>
void for_each_bit(const Signal& s, F&& f) noexcept;
// The smallest CAN FD data length (0..8, 12, 16, 20, 24, 32, 48, 64) >= bytes; 64 above.
[[nodiscard]] std::size_t fd_length(std::size_t bytes) noexcept;

// The raw bits of the signal (zero-extended). data must hold bytes_needed(s) bytes.
[[nodiscard]] std::uint64_t extract_raw(std::span<const std::uint8_t> data,
                                        const Signal& s) noexcept;
// Writes the low `length` bits of raw into the signal's bits; other bits are left as they are.
void insert_raw(std::span<std::uint8_t> data, const Signal& s, std::uint64_t raw) noexcept;

// The physical value: raw (sign-extended when signed) * scale + offset.
[[nodiscard]] double decode(std::span<const std::uint8_t> data, const Signal& s) noexcept;

enum class EncodeResult : std::uint8_t {
  kOk = 0,
  kSaturated = 1,  // outside the raw range: the nearest end was written
  kNotFinite = 2,  // NaN or infinite: nothing written
};
// Writes round((value - offset) / scale), saturated to the raw range.
EncodeResult encode(std::span<std::uint8_t> data, const Signal& s, double value) noexcept;

// ---- inline ----

template <typename F>
void for_each_bit(const Signal& s, F&& f) noexcept {
  if (s.order == ByteOrder::kLittle) {
    for (std::uint32_t k = s.length; k-- > 0;)
      f(s.start_bit + k);
  } else {
    std::uint32_t p = s.start_bit;
    for (std::uint32_t k = 0; k < s.length; ++k) {
      f(p);
      p = (p % 8U == 0U) ? p + 15U : p - 1U;
    }
  }
}

}  // namespace selfsense::drivers::can
