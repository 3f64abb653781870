// Recordings: the CSV format of docs/recording-format.md held in memory.
//
// A recording is a set of named columns of equal length (SI units: t s, E V/m, D C/m^2,
// S -, T Pa, temp degC; any other column is carried through untouched) plus the '#' comment
// lines that precede the header. Not real-time code: reading and writing allocate and throw.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace selfsense::io {

// Every error names the file, and where it applies the 1-based line and the column name:
// "R.csv:17: column 'E': not a number: 'abc'".
class RecordingError final : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Recording final {
 public:
  // Comment lines without the leading '#' (and one following space, if any).
  std::vector<std::string> comments{};

  [[nodiscard]] std::size_t rows() const noexcept;
  [[nodiscard]] std::size_t cols() const noexcept { return names_.size(); }
  [[nodiscard]] const std::vector<std::string>& names() const noexcept { return names_; }
  [[nodiscard]] bool has(std::string_view name) const noexcept {
    return index_of(name).has_value();
  }
  [[nodiscard]] std::optional<std::size_t> index_of(std::string_view name) const noexcept;

  // The column's samples; throws RecordingError naming the column if it is absent.
  [[nodiscard]] std::span<const double> column(std::string_view name) const;
  [[nodiscard]] std::span<double> column(std::string_view name);
  [[nodiscard]] std::span<const double> column(std::size_t index) const {
    return columns_.at(index);
  }

  // Appends a column, or replaces the values of an existing one of that name. Throws
  // std::invalid_argument if its length differs from the recording's row count.
  void set_column(std::string name, std::vector<double> values);

 private:
  std::vector<std::string> names_{};
  std::vector<std::vector<double>> columns_{};
};

struct ReadOptions {
  // Columns that must be present; the contract always requires t and E.
  std::vector<std::string> required{"t", "E"};
};

// Strict reader: a missing required column, a blank or duplicated column name, a non-numeric or
// non-finite cell, a row with the wrong number of cells, a t that does not strictly increase, a
// carriage return inside a line (not before its '\n') or an empty file throws RecordingError
// naming file, line and column. What it accepts, write_recording_csv() writes back.
[[nodiscard]] Recording read_recording_csv(const std::filesystem::path& path,
                                           const ReadOptions& options = {});

// Writes the comments, the header and every row with full double precision (round-trips
// exactly). Throws RecordingError if the file cannot be written.
void write_recording_csv(const Recording& recording, const std::filesystem::path& path);

}  // namespace selfsense::io
