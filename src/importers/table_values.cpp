#include "selfsense/importers/table_values.hpp"

#include <algorithm>
#include <cstddef>
#include <optional>
#include <stdexcept>
#include <string>

#include "selfsense/importers/import_text.hpp"

namespace selfsense::importers {

namespace {

bool all_numbers(const std::vector<std::string_view>& cells) {
  return std::all_of(cells.begin(), cells.end(),
                     [](std::string_view cell) { return parse_number(cell).has_value(); });
}

std::string column_list(const std::vector<std::string_view>& cells) {
  std::string out;
  for (const std::string_view cell : cells) {
    if (!out.empty()) out += ", ";
    out += trim(cell);
  }
  return out;
}

}  // namespace

std::vector<double> read_table_values(const std::filesystem::path& path) {
  const std::vector<std::string> lines = read_lines(path);
  const std::string file = path.string();
  std::optional<std::size_t> column;  // set by the first line that holds content
  std::vector<double> values;
  for (std::size_t k = 0; k < lines.size(); ++k) {
    const std::string_view line = trim(lines[k]);
    if (line.empty() || line.front() == '#') continue;
    const std::string where = file + ":" + std::to_string(k + 1);
    const std::vector<std::string_view> cells = split_cells(line, ',');
    if (!column) {
      if (all_numbers(cells)) {
        if (cells.size() != 1) {
          throw std::runtime_error(where + ": " + std::to_string(cells.size()) +
                                   " columns and no header naming a 'value' column");
        }
        column = 0;
      } else {
        const auto named = std::find_if(cells.begin(), cells.end(), [](std::string_view cell) {
          return trim(cell) == "value";
        });
        if (named == cells.end()) {
          throw std::runtime_error(where + ": no 'value' column (columns: " + column_list(cells) +
                                   ")");
        }
        column = static_cast<std::size_t>(named - cells.begin());
        continue;
      }
    }
    if (*column >= cells.size()) {
      throw std::runtime_error(where + ": " + std::to_string(cells.size()) +
                               " cells, the value is in column " + std::to_string(*column + 1));
    }
    const std::optional<double> value = parse_number(cells[*column]);
    if (!value) {
      throw std::runtime_error(where + ": '" + std::string(trim(cells[*column])) +
                               "' is not a number");
    }
    values.push_back(*value);
  }
  if (values.empty()) throw std::runtime_error(file + ": no values");
  return values;
}

std::vector<double> parse_number_list(std::string_view text, std::string_view what) {
  std::vector<double> values;
  for (const std::string_view cell : split_cells(text, ',')) {
    const std::optional<double> value = parse_number(cell);
    if (!value) {
      throw std::runtime_error(std::string(what) + ": '" + std::string(trim(cell)) +
                               "' is not a number");
    }
    values.push_back(*value);
  }
  return values;
}

}  // namespace selfsense::importers
