// Reader for generic delimited text (`selfsense import columns`): picks 1-based columns, names
// them, scales them to SI and, given a geometry, converts terminal quantities to field ones:
//   E = u / h        h: layer thickness [m]
//   D = q / (A * n)  A: electrode area of one layer [m^2], n: layers
//   S = x / L        L: active length [m]
//   T = F / A_mech   A_mech: mechanical cross-section [m^2]
// The terminal columns are kept beside the field ones. Where no column is named t, t is made
// from a sample rate. Not real-time code; errors name the file, line and column.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "selfsense/io/recording.hpp"

namespace selfsense::importers {

struct ColumnMap {
  std::size_t column{0};  // 1-based column in the file
  std::string name{};
  std::string unit{};  // as written; empty: no scaling
  double factor{1.0};  // to SI
};

// Parses "2:t:s,3:x:um,4:u:V"; the unit is optional. Throws std::invalid_argument naming the
// bad item (bad column number, empty or repeated name, unknown unit).
[[nodiscard]] std::vector<ColumnMap> parse_column_map(std::string_view map);

// The delimiter as a user writes it: one character, "tab" (or "\\t") or "space" (or
// "whitespace"; ' ', runs of blanks and tabs). Throws std::invalid_argument otherwise.
[[nodiscard]] char parse_delimiter(std::string_view text);

struct ColumnsOptions {
  char delimiter{','};  // ' ': runs of blanks and tabs
  std::vector<ColumnMap> map{};
  std::size_t skip_rows{0};       // lines before the data (headers)
  std::size_t first_row{1};       // 1-based data rows to keep, after skip_rows
  std::size_t last_row{0};        // 0: to the end
  double sample_rate_hz{0.0};     // makes t = (row - first_row) / rate where no column is t
  double layer_thickness_m{0.0};  // 0: not given (no conversion of that quantity)
  double electrode_area_m2{0.0};
  double layers{1.0};
  double active_length_m{0.0};
  double cross_section_m2{0.0};
};

[[nodiscard]] io::Recording import_columns(const std::filesystem::path& path,
                                           const ColumnsOptions& options);

}  // namespace selfsense::importers
