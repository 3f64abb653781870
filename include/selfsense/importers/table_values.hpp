// The values of a wave table for `selfsense ctl wave table --table FILE`: one value per line,
// or a CSV whose header names a `value` column. Blank lines and lines starting with '#' are
// skipped. Throws std::runtime_error naming the file and line of the first problem.
#pragma once

#include <filesystem>
#include <string_view>
#include <vector>

namespace selfsense::importers {

[[nodiscard]] std::vector<double> read_table_values(const std::filesystem::path& path);

// "0,1e-4,-2e-4" as numbers; throws std::runtime_error naming `what` and the bad cell.
[[nodiscard]] std::vector<double> parse_number_list(std::string_view text, std::string_view what);

}  // namespace selfsense::importers
