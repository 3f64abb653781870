#include "selfsense/importers/import_columns.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <system_error>
#include <utility>

#include "selfsense/base/format_number.hpp"
#include "selfsense/importers/import_text.hpp"

namespace selfsense::importers {
namespace {

using base::format_number;

std::string where(const std::string& file, std::size_t line, const ColumnMap& m) {
  return file + ":" + std::to_string(line) + ": column " + std::to_string(m.column) + " ('" +
         m.name + "'): ";
}

// Appends `field` = `terminal` / `divisor` when the terminal column exists, the field one does
// not and the divisor (a geometry length or area) was given. Row k came from line first_line + k;
// a quotient beyond the range of a double is an error naming it (a recording holds finite
// numbers only).
void convert(io::Recording& rec, const char* terminal, const char* field, double divisor,
             const char* what, const std::string& file, std::size_t first_line) {
  if (divisor <= 0.0 || !rec.has(terminal) || rec.has(field)) return;
  const auto c = rec.column(terminal);
  std::vector<double> out(c.size());
  std::transform(c.begin(), c.end(), out.begin(), [divisor](double v) { return v / divisor; });
  const auto bad = std::find_if(out.begin(), out.end(), [](double v) { return !std::isfinite(v); });
  if (bad != out.end()) {
    const auto k = static_cast<std::size_t>(bad - out.begin());
    throw io::RecordingError(file + ":" + std::to_string(first_line + k) + ": " + field + " = " +
                             terminal + " / " + format_number(divisor) + " = " +
                             format_number(c[k]) + " / " + format_number(divisor) +
                             " is beyond the range of a double");
  }
  rec.set_column(field, std::move(out));
  rec.comments.push_back(std::string(field) + " = " + terminal + " / " + format_number(divisor) +
                         " (" + what + ")");
}

}  // namespace

char parse_delimiter(std::string_view text) {
  if (text == "tab" || text == "\\t" || text == "\t") return '\t';
  if (text == "space" || text == "whitespace" || text == " ") return ' ';
  if (text.size() == 1) return text.front();
  throw std::invalid_argument("--delimiter: '" + std::string(text) +
                              "' is not one character, 'tab' or 'space'");
}

std::vector<ColumnMap> parse_column_map(std::string_view map) {
  std::vector<ColumnMap> out;
  for (const std::string_view item : split_cells(map, ',')) {
    const std::vector<std::string_view> parts = split_cells(item, ':');
    const std::string text = "--map item '" + std::string(item) + "': ";
    if (parts.size() < 2 || parts.size() > 3) {
      throw std::invalid_argument(text + "expected COLUMN:NAME or COLUMN:NAME:UNIT");
    }
    ColumnMap m;
    const std::string_view col = trim(parts[0]);
    const auto [ptr, error] = std::from_chars(col.data(), col.data() + col.size(), m.column);
    if (error != std::errc{} || ptr != col.data() + col.size() || m.column == 0) {
      throw std::invalid_argument(text + "column '" + std::string(col) +
                                  "' is not a 1-based number");
    }
    m.name = trim(parts[1]);
    if (m.name.empty() || m.name.starts_with('#')) {
      throw std::invalid_argument(text + "empty name or name starting with '#'");
    }
    if (std::any_of(out.begin(), out.end(), [&](const ColumnMap& o) { return o.name == m.name; })) {
      throw std::invalid_argument(text + "name '" + m.name + "' given twice");
    }
    m.unit = parts.size() == 3 ? std::string(trim(parts[2])) : std::string();
    const std::optional<double> factor = unit_factor(m.unit);
    if (!factor) {
      throw std::invalid_argument(text + "unknown unit '" + m.unit + "' (known: " + known_units() +
                                  ")");
    }
    m.factor = *factor;
    out.push_back(std::move(m));
  }
  if (out.empty()) throw std::invalid_argument("--map: no columns given");
  return out;
}

io::Recording import_columns(const std::filesystem::path& path, const ColumnsOptions& options) {
  const std::string file = path.string();
  const std::vector<std::string> lines = read_lines(path);
  std::size_t end = lines.size();
  while (end > options.skip_rows && trim(lines[end - 1]).empty())
    --end;
  const std::size_t first = options.skip_rows + options.first_row - 1;  // 0-based line
  std::size_t last = end;
  if (options.last_row > 0) last = std::min(end, options.skip_rows + options.last_row);
  if (options.first_row == 0 || first + 2 > last) {
    throw io::RecordingError(file + ": fewer than 2 data rows selected (" +
                             std::to_string(end > options.skip_rows ? end - options.skip_rows : 0) +
                             " data rows after skipping " + std::to_string(options.skip_rows) +
                             ")");
  }
  const std::vector<ColumnMap>& map = options.map;
  const auto t_it =
      std::find_if(map.begin(), map.end(), [](const ColumnMap& m) { return m.name == "t"; });
  const auto t_index = static_cast<std::size_t>(t_it - map.begin());  // map.size(): none
  if (t_it == map.end() && options.sample_rate_hz <= 0.0) {
    throw io::RecordingError(file + ": no column is named t; give --sample-rate-hz");
  }
  std::vector<std::vector<double>> values(map.size());
  for (std::vector<double>& v : values)
    v.reserve(last - first);
  for (std::size_t j = first; j < last; ++j) {
    const std::vector<std::string_view> cells = split_cells(lines[j], options.delimiter);
    for (std::size_t i = 0; i < map.size(); ++i) {
      const ColumnMap& m = map[i];
      if (m.column > cells.size()) {
        throw io::RecordingError(where(file, j + 1, m) + "missing: the line has " +
                                 std::to_string(cells.size()) + " cells");
      }
      const std::optional<double> v = parse_number(cells[m.column - 1]);
      if (!v) {
        throw io::RecordingError(where(file, j + 1, m) + "not a number: '" +
                                 std::string(trim(cells[m.column - 1])) + "'");
      }
      const double si = *v * m.factor;
      if (!std::isfinite(si)) {
        throw io::RecordingError(where(file, j + 1, m) + format_number(*v) + " " + m.unit +
                                 " is beyond the range of a double in SI units");
      }
      values[i].push_back(si);
      if (i == t_index && values[i].size() > 1 && values[i].back() <= values[i].end()[-2]) {
        throw io::RecordingError(where(file, j + 1, m) + format_number(*v) + " does not increase");
      }
    }
  }
  io::Recording rec;
  rec.comments.push_back("imported by selfsense import columns from " + file + ", lines " +
                         std::to_string(first + 1) + " to " + std::to_string(last));
  if (t_it == map.end()) {
    std::vector<double> t(last - first);
    for (std::size_t k = 0; k < t.size(); ++k) {
      t[k] = static_cast<double>(k) / options.sample_rate_hz;
    }
    rec.set_column("t", std::move(t));
    rec.comments.push_back("t = (row - first row) / " + format_number(options.sample_rate_hz) +
                           " Hz");
  }
  for (std::size_t i = 0; i < map.size(); ++i) {
    rec.comments.push_back(map[i].name + " = column " + std::to_string(map[i].column) +
                           (map[i].unit.empty() ? "" : " [" + map[i].unit + "]") + " * " +
                           format_number(map[i].factor));
    rec.set_column(map[i].name, std::move(values[i]));
  }
  const std::size_t line = first + 1;  // of the first row
  convert(rec, "u", "E", options.layer_thickness_m, "layer thickness [m]", file, line);
  convert(rec, "q", "D", options.electrode_area_m2 * options.layers,
          "electrode area [m^2] * layers", file, line);
  convert(rec, "x", "S", options.active_length_m, "active length [m]", file, line);
  convert(rec, "F", "T", options.cross_section_m2, "mechanical cross-section [m^2]", file, line);
  return rec;
}

}  // namespace selfsense::importers
