// The Modbus register map of the transducer: where E, D (and the reference S, T) are read and
// where the command E is written, and how a value sits in 16-bit registers. Shared by the driver
// (include/selfsense/drivers/modbus/modbus_driver.hpp) and the simulated device (`selfsense
// sim-device`), so both sides encode with the same code.
//
// A value is stored as raw = (value - offset) / scale in one register (int16, uint16) or two
// (int32, float32; `high-first` puts the high word at the lower address, the Modbus custom,
// `low-first` the other way round; bytes within a register are always big-endian, as the
// protocol says). Decoding: value = raw * scale + offset.
//
// encode() and decode() are pure and real-time safe (noexcept, no allocation).
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <string_view>

namespace selfsense::drivers::modbus {

enum class Function : std::uint8_t {
  kHolding = 0,  // holding registers: read 0x03, write 0x10
  kInput = 1,    // input registers: read 0x04 (read-only)
};
enum class RegisterType : std::uint8_t { kInt16 = 0, kUint16, kInt32, kFloat32 };
enum class WordOrder : std::uint8_t { kHighFirst = 0, kLowFirst };

[[nodiscard]] std::string_view to_string(Function f) noexcept;
[[nodiscard]] std::string_view to_string(RegisterType t) noexcept;
[[nodiscard]] std::string_view to_string(WordOrder w) noexcept;
// Registers a value of this type occupies: 1 or 2.
[[nodiscard]] int word_count(RegisterType t) noexcept;

struct RegisterSpec {
  bool enabled{false};
  int address{0};  // 0-based register address (mbpoll's -r is this + 1 unless -0)
  Function function{Function::kInput};
  RegisterType type{RegisterType::kFloat32};
  WordOrder word_order{WordOrder::kHighFirst};
  double scale{1.0};  // value = raw * scale + offset
  double offset{0.0};
  // Decoded values outside [min, max] are bad data (NaN and infinities always are).
  double min{-std::numeric_limits<double>::infinity()};
  double max{std::numeric_limits<double>::infinity()};

  // Empty when valid, otherwise "key: what" for the first violated constraint (keys relative to
  // the spec, e.g. "scale: must be finite and non-zero").
  [[nodiscard]] std::string problem() const;
};

enum class DecodeStatus : std::uint8_t { kOk = 0, kNotFinite, kOutOfRange };

struct Decoded {
  double value{std::numeric_limits<double>::quiet_NaN()};
  DecodeStatus status{DecodeStatus::kOk};
};

// words: the spec's word_count() registers as they sit on the bus, starting at its address.
[[nodiscard]] Decoded decode(const RegisterSpec& spec,
                             std::span<const std::uint16_t> words) noexcept;

// The registers for a value; false (words untouched) when the value is not finite, does not
// fit the type after scaling (integers are rounded to nearest, never wrapped or clamped) or
// the registers would not decode to a finite value (an extreme scale and offset).
[[nodiscard]] bool encode(const RegisterSpec& spec, double value,
                          std::span<std::uint16_t> words) noexcept;

// The transducer's registers. e and d are required; s_ref and t_ref optional (both or none);
// status (uint16, into InputSample::device_status) optional; temp (the stack's temperature
// [degC], into InputSample::temp_ref: the recording's `temp` column and the driver's
// has_temperature()) optional; command is required.
struct RegisterMap {
  RegisterSpec e{};
  RegisterSpec d{};
  RegisterSpec s_ref{};
  RegisterSpec t_ref{};
  RegisterSpec status{};
  RegisterSpec command{};
  RegisterSpec temp{};

  // The inputs in a fixed order (e, d, s_ref, t_ref, status, temp), for iteration.
  [[nodiscard]] std::array<const RegisterSpec*, 6> inputs() const noexcept {
    return {&e, &d, &s_ref, &t_ref, &status, &temp};
  }
  // Empty when valid, else "registers.KEY.FIELD: what" (required entries present, the command a
  // holding register, no two entries overlapping in the same table, every spec valid).
  [[nodiscard]] std::string problem() const;
};

// The map `selfsense sim-device` serves unless told otherwise (docs/drivers/modbus.md):
// input registers, float32 high word first, scale 1:
//   0-1 E [V/m], 2-3 D [C/m^2], 4-5 S [-], 6-7 T [Pa], 8 status (uint16)
// holding registers: 0-1 command E [V/m] (float32 high word first). No temperature.
[[nodiscard]] RegisterMap default_register_map();

// The map `selfsense sim-device` serves: the default map and the stack's temperature in input
// registers 9-10 [degC] (float32 high word first; a quiet NaN when the plant has no temperature
// model), which a driver reads only when its `registers` name `temp`.
[[nodiscard]] RegisterMap served_register_map();

}  // namespace selfsense::drivers::modbus
