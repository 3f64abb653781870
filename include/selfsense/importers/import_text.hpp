// Text helpers shared by the importers of foreign recordings (`selfsense import`): reading a
// file as numbered lines, splitting, strict number parsing and unit factors to SI.
// Not real-time code: everything here allocates and throws io::RecordingError.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace selfsense::importers {

// The file's lines without their line ends ("\n" or "\r\n"); line k (1-based) is lines[k - 1].
// Throws io::RecordingError naming the file if it cannot be read or is empty.
[[nodiscard]] std::vector<std::string> read_lines(const std::filesystem::path& path);

[[nodiscard]] std::string_view trim(std::string_view s) noexcept;

// Splits at every `delimiter`; ' ' splits at runs of blanks and tabs and drops empty cells.
[[nodiscard]] std::vector<std::string_view> split_cells(std::string_view line, char delimiter);

// The whole (trimmed) cell as a finite double; a leading '+' is accepted. nullopt otherwise.
[[nodiscard]] std::optional<double> parse_number(std::string_view cell) noexcept;

// Factor from `unit` to SI: "um" -> 1e-6 (m), "uC/cm2" -> 1e-2 (C/m^2), "kV" -> 1e3 (V).
// Empty, "1" and "-" are 1. nullopt for an unknown unit.
[[nodiscard]] std::optional<double> unit_factor(std::string_view unit) noexcept;

// The units unit_factor knows, for messages.
[[nodiscard]] std::string known_units();

}  // namespace selfsense::importers
