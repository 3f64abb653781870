#include "selfsense/importers/import_text.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <system_error>
#include <utility>

#include "selfsense/io/recording.hpp"

namespace selfsense::importers {
namespace {

struct Unit {
  std::string_view name;
  double factor;
};

// Base units with SI prefixes spelled out; "u" stands for micro.
constexpr std::array kUnits{
    Unit{"s", 1.0},    Unit{"ms", 1e-3},   Unit{"us", 1e-6},     Unit{"min", 60.0},
    Unit{"h", 3600.0}, Unit{"V", 1.0},     Unit{"mV", 1e-3},     Unit{"kV", 1e3},
    Unit{"V/m", 1.0},  Unit{"kV/mm", 1e6}, Unit{"MV/m", 1e6},    Unit{"V/mm", 1e3},
    Unit{"m", 1.0},    Unit{"mm", 1e-3},   Unit{"um", 1e-6},     Unit{"nm", 1e-9},
    Unit{"C", 1.0},    Unit{"mC", 1e-3},   Unit{"uC", 1e-6},     Unit{"nC", 1e-9},
    Unit{"pC", 1e-12}, Unit{"C/m2", 1.0},  Unit{"uC/cm2", 1e-2}, Unit{"mC/m2", 1e-3},
    Unit{"A", 1.0},    Unit{"mA", 1e-3},   Unit{"uA", 1e-6},     Unit{"nA", 1e-9},
    Unit{"N", 1.0},    Unit{"mN", 1e-3},   Unit{"kN", 1e3},      Unit{"Pa", 1.0},
    Unit{"kPa", 1e3},  Unit{"MPa", 1e6},   Unit{"degC", 1.0},    Unit{"ppm", 1e-6},
    Unit{"%", 1e-2},   Unit{"1", 1.0},     Unit{"-", 1.0},
};

}  // namespace

std::vector<std::string> read_lines(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw io::RecordingError(path.string() + ": cannot open");
  std::vector<std::string> lines;
  std::string line;
  while (std::getline(file, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    lines.push_back(std::move(line));
  }
  if (file.bad()) throw io::RecordingError(path.string() + ": read error");
  if (lines.empty()) throw io::RecordingError(path.string() + ": empty file");
  return lines;
}

std::string_view trim(std::string_view s) noexcept {
  const auto blank = [](char c) { return c == ' ' || c == '\t'; };
  while (!s.empty() && blank(s.front()))
    s.remove_prefix(1);
  while (!s.empty() && blank(s.back()))
    s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> split_cells(std::string_view line, char delimiter) {
  std::vector<std::string_view> cells;
  if (delimiter == ' ') {
    std::size_t k = 0;
    while (k < line.size()) {
      const std::size_t start = line.find_first_not_of(" \t", k);
      if (start == std::string_view::npos) break;
      const std::size_t end = std::min(line.find_first_of(" \t", start), line.size());
      cells.push_back(line.substr(start, end - start));
      k = end;
    }
    return cells;
  }
  std::size_t start = 0;
  for (;;) {
    const std::size_t end = line.find(delimiter, start);
    cells.push_back(line.substr(start, end == std::string_view::npos ? end : end - start));
    if (end == std::string_view::npos) return cells;
    start = end + 1;
  }
}

std::optional<double> parse_number(std::string_view cell) noexcept {
  cell = trim(cell);
  if (!cell.empty() && cell.front() == '+') cell.remove_prefix(1);
  if (cell.empty()) return std::nullopt;
  double value = 0.0;
  const auto [ptr, error] = std::from_chars(cell.data(), cell.data() + cell.size(), value);
  if (error != std::errc{} || ptr != cell.data() + cell.size() || !std::isfinite(value)) {
    return std::nullopt;
  }
  return value;
}

std::optional<double> unit_factor(std::string_view unit) noexcept {
  unit = trim(unit);
  if (unit.empty()) return 1.0;
  for (const Unit& u : kUnits) {
    if (u.name == unit) return u.factor;
  }
  return std::nullopt;
}

std::string known_units() {
  std::string out;
  for (const Unit& u : kUnits) {
    if (!out.empty()) out += ' ';
    out += u.name;
  }
  return out;
}

}  // namespace selfsense::importers
