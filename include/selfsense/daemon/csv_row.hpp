// Loop samples as rows of a contract recording (docs/recorder.md, "File format"): the column names,
// the row text, and the one way a row may be lengthened without changing its meaning.
//
// Columns, in this order:
//   t, E, D, T_hat, S_hat, setpoint, command, state, [S, T,] [temp,] [temp_equivalent,] mode,
//   faults, estimate_status, driver_status, nonfinite, cycle
// S and T only when the layout has references; temp (the stack's temperature from the driver,
// degC) only when the driver gives one; temp_equivalent (the adaptation's equivalent
// temperature, degC) only when the loop adapts. The contract reader accepts finite numbers only,
// so a NaN or infinite value (a channel the loop did not have, or a bad input) is written as 0
// and flagged by a bit in `nonfinite`: E 1, D 2, T_hat 4, S_hat 8, setpoint 16, command 32,
// S 64, T 128, temp 256, temp_equivalent 512. t is never substituted: the recorder does not
// write a row without a finite t.
// Doubles use the shortest text that reads back to the same bits.
//
// Real-time safe: format() and pad() (no allocation, no exception); they run on the writer
// thread, not the loop, but cost nothing beyond the formatting.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "selfsense/runtime/loop_sample.hpp"

namespace selfsense::daemon {

// No row is longer: 11 doubles of at most 24 characters (264), 7 integers (at most 20 + 10 + 3 +
// 3 + 5 + 4 + 1 = 46), 18 separators: 328.
inline constexpr std::size_t kMaxRowBytes = 384;

namespace nonfinite {
inline constexpr std::uint32_t kE = 1U << 0U;
inline constexpr std::uint32_t kD = 1U << 1U;
inline constexpr std::uint32_t kTHat = 1U << 2U;
inline constexpr std::uint32_t kSHat = 1U << 3U;
inline constexpr std::uint32_t kSetpoint = 1U << 4U;
inline constexpr std::uint32_t kCommand = 1U << 5U;
inline constexpr std::uint32_t kS = 1U << 6U;
inline constexpr std::uint32_t kT = 1U << 7U;
inline constexpr std::uint32_t kTemp = 1U << 8U;
inline constexpr std::uint32_t kTempEquivalent = 1U << 9U;
}  // namespace nonfinite

class RowFormat final {
 public:
  explicit RowFormat(bool references) noexcept : references_(references) {}
  RowFormat(bool references, bool temperature, bool temperature_equivalent) noexcept
      : references_(references),
        temperature_(temperature),
        temperature_equivalent_(temperature_equivalent) {}

  [[nodiscard]] bool references() const noexcept { return references_; }
  [[nodiscard]] bool temperature() const noexcept { return temperature_; }
  [[nodiscard]] bool temperature_equivalent() const noexcept { return temperature_equivalent_; }
  [[nodiscard]] std::vector<std::string> column_names() const;
  // The '#' comment lines (each given without '#') and the header row, '\n'-terminated.
  [[nodiscard]] std::string header_block(const std::vector<std::string>& comments) const;

  // Writes the row, '\n' included, to out (room for kMaxRowBytes); returns its length.
  std::size_t format(const runtime::LoopSample& sample, char* out) const noexcept;

  // Lengthens a formatted row by `extra` bytes without changing any value: leading zeros in
  // its last cell (cycle). out must have room for length + extra. Returns the new length.
  static std::size_t pad(char* row, std::size_t length, std::size_t extra) noexcept;

 private:
  bool references_{true};
  bool temperature_{false};
  bool temperature_equivalent_{false};
};

}  // namespace selfsense::daemon
