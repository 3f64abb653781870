#include "selfsense/importers/import_aixacct.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <map>
#include <string_view>
#include <utility>
#include <vector>

#include "selfsense/base/format_number.hpp"
#include "selfsense/importers/import_text.hpp"

namespace selfsense::importers {
namespace {

using base::format_number;

struct Block {
  std::size_t header{0};  // index into the lines of the "Time [s]" header
  std::vector<std::pair<std::string, std::string>> metadata{};
  std::map<std::string, std::size_t, std::less<>> meta_line{};  // key -> 1-based line
};

// The "Table <n>" line starts a data block when metadata lines lead to a "Time [s]" header
// before any blank line (the summary's "Table 1" is followed by its own header instead).
std::optional<Block> data_block(const std::vector<std::string>& lines, std::size_t at) {
  Block b;
  for (std::size_t j = at + 1; j < lines.size(); ++j) {
    const std::string_view line = trim(lines[j]);
    if (line.empty()) return std::nullopt;
    if (line.starts_with("Time [s]")) {
      b.header = j;
      return b;
    }
    const std::size_t colon = line.find(": ");
    if (colon == std::string_view::npos && !line.ends_with(':')) return std::nullopt;
    const std::size_t end = colon == std::string_view::npos ? line.size() - 1 : colon;
    b.metadata.emplace_back(std::string(line.substr(0, end)),
                            std::string(trim(line.substr(std::min(end + 1, line.size())))));
    b.meta_line.emplace(b.metadata.back().first, j + 1);
  }
  return std::nullopt;
}

std::string at(const std::string& file, std::size_t line) {
  return file + ":" + std::to_string(line) + ": ";
}

// Finite, positive number of metadata `key`, or nullopt if the block has no such key.
std::optional<double> meta_number(const Block& b, const std::string& file, std::string_view key) {
  const auto it = b.meta_line.find(key);
  if (it == b.meta_line.end()) return std::nullopt;
  const auto kv = std::find_if(b.metadata.begin(), b.metadata.end(),
                               [&](const auto& p) { return p.first == key; });
  const std::optional<double> v = parse_number(kv->second);
  if (!v || *v <= 0.0) {
    throw io::RecordingError(at(file, it->second) + "'" + std::string(key) +
                             "': not a positive number: '" + kv->second + "'");
  }
  return v;
}

struct Columns {
  std::size_t time{0}, vplus{0}, vminus{0}, current{0}, polarization{0}, displacement{0};
  bool has_vminus{false};
  std::size_t count{0};
};

Columns find_columns(std::string_view header, const std::string& file, std::size_t line) {
  std::vector<std::string_view> names = split_cells(header, '\t');
  while (!names.empty() && trim(names.back()).empty())
    names.pop_back();
  Columns c;
  c.count = names.size();
  const auto find = [&](std::string_view name, bool required) -> std::optional<std::size_t> {
    const auto it = std::find_if(names.begin(), names.end(),
                                 [&](std::string_view n) { return trim(n) == name; });
    if (it != names.end()) return static_cast<std::size_t>(it - names.begin());
    if (required) {
      throw io::RecordingError(at(file, line) + "header has no column '" + std::string(name) + "'");
    }
    return std::nullopt;
  };
  c.time = *find("Time [s]", true);
  c.vplus = *find("V+ [V]", true);
  c.current = *find("I1 [A]", true);
  c.polarization = *find("P1 [uC/cm2]", true);
  c.displacement = *find("D1 [nm]", true);
  if (const auto v = find("V- [V]", false)) {
    c.vminus = *v;
    c.has_vminus = true;
  }
  return c;
}

struct Raw {
  std::vector<double> t{}, u{}, i{}, p{}, x{};
};

Raw read_rows(const std::vector<std::string>& lines, std::size_t first, const Columns& c,
              const std::string& file) {
  Raw r;
  std::vector<std::string_view> names = split_cells(lines[first - 1], '\t');
  for (std::size_t j = first; j < lines.size(); ++j) {
    const std::string_view line = trim(lines[j]);
    if (line.empty() || line.starts_with("Table ")) break;
    std::vector<std::string_view> cells = split_cells(lines[j], '\t');
    while (cells.size() > c.count && trim(cells.back()).empty())
      cells.pop_back();
    if (cells.size() != c.count) {
      throw io::RecordingError(at(file, j + 1) + std::to_string(cells.size()) +
                               " cells, the header has " + std::to_string(c.count));
    }
    const auto cell = [&](std::size_t col) {
      const std::optional<double> v = parse_number(cells[col]);
      if (!v) {
        throw io::RecordingError(at(file, j + 1) + "column '" + std::string(trim(names[col])) +
                                 "': not a number: '" + std::string(trim(cells[col])) + "'");
      }
      return *v;
    };
    const double t = cell(c.time);
    if (!r.t.empty() && t <= r.t.back()) {
      throw io::RecordingError(at(file, j + 1) + "column 'Time [s]': " + format_number(t) +
                               " does not increase");
    }
    r.t.push_back(t);
    r.u.push_back(cell(c.vplus) - (c.has_vminus ? cell(c.vminus) : 0.0));
    r.i.push_back(cell(c.current));
    r.p.push_back(cell(c.polarization));
    r.x.push_back(cell(c.displacement));
  }
  if (r.t.size() < 2) throw io::RecordingError(at(file, first + 1) + "block has fewer than 2 rows");
  return r;
}

std::vector<double> scaled(const std::vector<double>& v, double factor) {
  std::vector<double> out(v.size());
  std::transform(v.begin(), v.end(), out.begin(), [factor](double x) { return x * factor; });
  return out;
}

}  // namespace

AixacctImport import_aixacct(const std::filesystem::path& path, const AixacctOptions& options) {
  const std::string file = path.string();
  const std::vector<std::string> lines = read_lines(path);
  const std::string wanted = "Table " + std::to_string(options.block);
  std::optional<Block> block;
  std::string found;
  for (std::size_t k = 0; k < lines.size() && !block; ++k) {
    const std::string_view line = trim(lines[k]);
    if (!line.starts_with("Table ")) continue;
    std::optional<Block> b = data_block(lines, k);
    if (!b) continue;
    if (line == wanted) block = std::move(b);
    found += (found.empty() ? "" : ", ") + std::string(line.substr(6));
  }
  if (!block) {
    throw io::RecordingError(file + ": no data block '" + wanted +
                             "' (data blocks: " + (found.empty() ? "none" : found) + ")");
  }
  const Columns columns = find_columns(lines[block->header], file, block->header + 1);
  const Raw raw = read_rows(lines, block->header + 1, columns, file);

  const std::optional<double> thickness_nm = meta_number(*block, file, "Thickness [nm]");
  const std::optional<double> area_mm2 = meta_number(*block, file, "Area [mm2]");
  const double h =
      options.thickness_m ? *options.thickness_m : (thickness_nm ? *thickness_nm / 1e9 : 0.0);
  const double area = (options.area_mm2 ? *options.area_mm2 : area_mm2.value_or(0.0)) / 1e6;
  if (h <= 0.0) {
    throw io::RecordingError(file + ": block " + std::to_string(options.block) +
                             " has no 'Thickness [nm]'; give --thickness-m");
  }
  AixacctImport out;
  double i0 = options.current_offset_a.value_or(0.0);
  if (options.detrend_charge) {
    const std::size_t n = raw.i.size();
    const auto tail = std::max<std::size_t>(
        1, static_cast<std::size_t>(options.detrend_tail * static_cast<double>(n)));
    double sum = 0.0;
    for (std::size_t k = n - tail; k < n; ++k)
      sum += raw.i[k];
    i0 = sum / static_cast<double>(tail);
  }
  if (i0 != 0.0 && area <= 0.0) {
    throw io::RecordingError(file + ": block " + std::to_string(options.block) +
                             " has no 'Area [mm2]'; give --area-mm2 to remove a current offset");
  }
  out.offset_current_a = i0;
  std::vector<double> d(raw.p.size());
  for (std::size_t k = 0; k < d.size(); ++k) {
    d[k] = raw.p[k] * 1e-2 - (i0 == 0.0 ? 0.0 : i0 * (raw.t[k] - raw.t.front()) / area);
  }

  io::Recording& rec = out.recording;
  rec.comments.push_back("imported by selfsense import aixacct from " + file + ", block " +
                         std::to_string(options.block));
  rec.comments.emplace_back(
      "E = (V+ - V-) / h, D = P1 * 1e-2 - I0 * (t - t0) / A, S = D1 * 1e-9 / h");
  rec.comments.push_back("h = " + format_number(h) + " m, A = " + format_number(area) +
                         " m^2, I0 = " + format_number(i0) + " A");
  rec.comments.emplace_back("raw columns: u [V] = V+ - V-, I [A] = I1, P1 [uC/cm2], D1 [nm]");
  for (const auto& [key, value] : block->metadata) {
    if (key == "SampleName") out.sample_name = value;
    std::string comment = "aixacct " + key;
    comment += ": ";
    comment += value;
    // A carriage return inside a header line (lines split on '\n' only keep it) would break the
    // comment over two lines of the recording, which the writer refuses.
    std::replace(comment.begin(), comment.end(), '\r', ' ');
    rec.comments.push_back(std::move(comment));
  }
  rec.set_column("t", raw.t);
  rec.set_column("E", scaled(raw.u, 1.0 / h));
  rec.set_column("D", std::move(d));
  rec.set_column("S", scaled(raw.x, 1e-9 / h));
  rec.set_column("u", raw.u);
  rec.set_column("I", raw.i);
  rec.set_column("P1", raw.p);
  rec.set_column("D1", raw.x);
  // Finite cells can still give a value beyond the range of a double (V+ - V-, / h); a
  // recording holds finite numbers only. Row k is line header + 2 + k (1-based).
  for (std::size_t j = 0; j < rec.cols(); ++j) {
    const auto c = rec.column(j);
    const auto bad = std::find_if(c.begin(), c.end(), [](double v) { return !std::isfinite(v); });
    if (bad == c.end()) continue;
    const auto k = static_cast<std::size_t>(bad - c.begin());
    throw io::RecordingError(at(file, block->header + 2 + k) + "column '" + rec.names()[j] +
                             "': " + format_number(*bad) + " after conversion (" + rec.comments[1] +
                             ", h = " + format_number(h) + " m)");
  }
  return out;
}

}  // namespace selfsense::importers
