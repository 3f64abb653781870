// Strict CSV reader and writer for recordings (format: docs/recording-format.md).
//
// The reader maps the whole file and parses it in place with std::from_chars: no allocation
// per cell, columns reserved from a count of the line breaks. Rows take a fast path that only
// checks; when a check fails, a slow path splits the row again to say exactly what is wrong.
// The writer checks everything first, then formats values with the shortest std::to_chars form
// (which reads back to the same bits) into a reused buffer written in large pieces.
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <fstream>
#include <string>
#include <utility>

#include "selfsense/base/errno_text.hpp"
#include "selfsense/base/format_number.hpp"
#include "selfsense/io/recording.hpp"

namespace selfsense::io {

// ---------------------------------------------------------------------------------------------
// Recording

std::size_t Recording::rows() const noexcept {
  return columns_.empty() ? 0 : columns_.front().size();
}

std::optional<std::size_t> Recording::index_of(std::string_view name) const noexcept {
  const auto it = std::find(names_.begin(), names_.end(), name);
  if (it == names_.end()) return std::nullopt;
  return static_cast<std::size_t>(it - names_.begin());
}

std::span<const double> Recording::column(std::string_view name) const {
  const auto index = index_of(name);
  if (!index) throw RecordingError("no column '" + std::string(name) + "'");
  return columns_[*index];
}

std::span<double> Recording::column(std::string_view name) {
  const auto index = index_of(name);
  if (!index) throw RecordingError("no column '" + std::string(name) + "'");
  return columns_[*index];
}

void Recording::set_column(std::string name, std::vector<double> values) {
  // The first column fixes the row count; every later one must match it, replacements included.
  if (!columns_.empty() && values.size() != rows()) {
    throw std::invalid_argument("set_column('" + name + "'): " + std::to_string(values.size()) +
                                " values, but the recording has " + std::to_string(rows()) +
                                " rows");
  }
  if (const auto index = index_of(name)) {
    columns_[*index] = std::move(values);
    return;
  }
  names_.push_back(std::move(name));
  columns_.push_back(std::move(values));
}

namespace {

constexpr std::string_view kTimeColumn = "t";
constexpr std::string_view kUtf8Bom = "\xEF\xBB\xBF";
// Longest shortest-form double ("-2.2250738585072014e-308") is 24 characters.
constexpr std::size_t kMaxNumberChars = 24;
// Cells quoted in messages are cut so that a runaway line cannot flood the terminal.
constexpr std::size_t kMaxQuotedChars = 40;

using base::errno_text;
using base::format_number;

[[noreturn]] void fail(const std::string& file, std::size_t line, std::string_view what) {
  throw RecordingError(file + ":" + std::to_string(line) + ": " + std::string(what));
}

[[noreturn]] void fail(const std::string& file, std::size_t line, std::string_view column,
                       std::string_view what) {
  fail(file, line, "column '" + std::string(column) + "': " + std::string(what));
}

// Appends piecewise: GCC 12 reports a false -Wrestrict for "'" + std::string(...) once inlined.
std::string quote_text(std::string_view text) {
  std::string quoted(1, '\'');
  quoted.append(text.substr(0, kMaxQuotedChars));
  if (text.size() > kMaxQuotedChars) quoted += "...";
  quoted += '\'';
  return quoted;
}

bool is_blank(std::string_view line) noexcept {
  return line.find_first_not_of(" \t\r") == std::string_view::npos;
}

bool rest_is_blank(const char* pos, const char* end) noexcept {
  return std::all_of(pos, end,
                     [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; });
}

// Returns the line at pos without its '\n' or "\r\n" and moves pos to the next line.
std::string_view next_line(const char*& pos, const char* end) noexcept {
  const char* const start = pos;
  const char* const newline =
      std::char_traits<char>::find(start, static_cast<std::size_t>(end - start), '\n');
  const char* line_end = newline == nullptr ? end : newline;
  pos = newline == nullptr ? end : newline + 1;
  if (line_end != start && line_end[-1] == '\r') --line_end;
  return {start, static_cast<std::size_t>(line_end - start)};
}

std::vector<std::string_view> split_cells(std::string_view line) {
  std::vector<std::string_view> cells;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    if (comma == std::string_view::npos) {
      cells.push_back(line.substr(start));
      return cells;
    }
    cells.push_back(line.substr(start, comma - start));
    start = comma + 1;
  }
}

// The whole file as one block of text. Regular files are mapped read-only (MAP_POPULATE maps
// the page cache in one go): copying 100 MB into fresh heap pages took longer than parsing it.
// Anything else (pipes, /dev/stdin) or a failed mapping falls back to reading. Like any mapped
// reader, truncating the file while it is being parsed raises SIGBUS; recordings are written
// once and then only read, so the speed is worth that.
class FileText final {
 public:
  FileText(const std::filesystem::path& path, const std::string& file) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw RecordingError(file + ": cannot open: " + errno_text(errno));
    try {
      load(fd, file);
    } catch (...) {
      ::close(fd);
      throw;
    }
    ::close(fd);
  }
  ~FileText() {
    if (map_ != nullptr) ::munmap(map_, map_size_);
  }
  FileText(const FileText&) = delete;
  FileText& operator=(const FileText&) = delete;
  FileText(FileText&&) = delete;
  FileText& operator=(FileText&&) = delete;

  [[nodiscard]] std::string_view text() const noexcept {
    if (map_ != nullptr) return {static_cast<const char*>(map_), map_size_};
    return copy_;
  }

 private:
  void load(int fd, const std::string& file) {
    struct stat status {};
    if (::fstat(fd, &status) != 0)
      throw RecordingError(file + ": cannot read: " + errno_text(errno));
    if (S_ISDIR(status.st_mode)) throw RecordingError(file + ": cannot read: is a directory");
    if (S_ISREG(status.st_mode) && status.st_size > 0) {
      const auto size = static_cast<std::size_t>(status.st_size);
      void* const map = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0);
      if (map != MAP_FAILED) {
        map_ = map;
        map_size_ = size;
        return;
      }
    }
    std::array<char, std::size_t{1} << 16U> chunk{};
    while (true) {
      const ssize_t got = ::read(fd, chunk.data(), chunk.size());
      if (got == 0) return;
      if (got < 0) {
        if (errno == EINTR) continue;
        throw RecordingError(file + ": cannot read: " + errno_text(errno));
      }
      copy_.append(chunk.data(), static_cast<std::size_t>(got));
    }
  }

  void* map_{nullptr};
  std::size_t map_size_{0};
  std::string copy_{};
};

std::vector<std::string> parse_header(std::string_view line, const std::string& file,
                                      std::size_t line_number) {
  std::vector<std::string> names;
  for (const std::string_view cell : split_cells(line)) {
    const std::string which = " (column " + std::to_string(names.size() + 1) + " of the header)";
    if (cell.empty()) fail(file, line_number, "empty column name" + which);
    if (is_blank(cell)) fail(file, line_number, "blank column name " + quote_text(cell) + which);
    // A carriage return inside a line reads as a line break in other tools, and the writer
    // refuses it: a file that could not be written back is not accepted either.
    if (cell.find('\r') != std::string_view::npos) {
      fail(file, line_number, "carriage return inside column name " + quote_text(cell) + which);
    }
    if (std::find(names.begin(), names.end(), cell) != names.end()) {
      fail(file, line_number, "duplicate column '" + std::string(cell) + "' in the header");
    }
    names.emplace_back(cell);
  }
  return names;
}

void check_required(const std::vector<std::string>& names, const ReadOptions& options,
                    const std::string& file, std::size_t line_number) {
  for (const std::string& wanted : options.required) {
    if (std::find(names.begin(), names.end(), wanted) != names.end()) continue;
    std::string message = "missing required column '" + wanted + "' (the header has: ";
    for (std::size_t j = 0; j < names.size(); ++j) {
      if (j > 0) message += ", ";
      message += names[j];
    }
    message += ')';
    fail(file, line_number, message);
  }
}

// Slow path, reached only once a row failed the fast checks: names the first problem.
[[noreturn]] void explain_bad_row(std::string_view line, const std::vector<std::string>& names,
                                  const std::string& file, std::size_t line_number) {
  const std::vector<std::string_view> cells = split_cells(line);
  if (cells.size() != names.size()) {
    fail(file, line_number,
         "expected " + std::to_string(names.size()) + " cells (one per column), found " +
             std::to_string(cells.size()));
  }
  for (std::size_t j = 0; j < cells.size(); ++j) {
    const std::string_view cell = cells[j];
    if (cell.empty()) fail(file, line_number, names[j], "empty cell");
    double value = 0.0;
    const auto [ptr, error] = std::from_chars(cell.data(), cell.data() + cell.size(), value);
    if (error == std::errc::result_out_of_range) {
      fail(file, line_number, names[j], "out of the range of a double: " + quote_text(cell));
    }
    if (error != std::errc{} || ptr != cell.data() + cell.size()) {
      fail(file, line_number, names[j], "not a number: " + quote_text(cell));
    }
    if (!std::isfinite(value)) {
      fail(file, line_number, names[j], "not a finite number: " + quote_text(cell));
    }
  }
  fail(file, line_number, "malformed row");  // unreachable while fast and slow paths agree
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Reader

Recording read_recording_csv(const std::filesystem::path& path, const ReadOptions& options) {
  const std::string file = path.string();
  const FileText file_text(path, file);
  const std::string_view data = file_text.text();
  const char* pos = data.data();
  const char* const end = data.data() + data.size();
  // Every leading byte-order mark (a file saved twice by a tool that adds one): a second one
  // kept in the first column's name would not survive a write and a read.
  while (std::string_view(pos, static_cast<std::size_t>(end - pos)).starts_with(kUtf8Bom))
    pos += kUtf8Bom.size();
  if (rest_is_blank(pos, end)) throw RecordingError(file + ": empty file: no header row");

  Recording recording;
  std::size_t line_number = 0;
  std::string_view header;
  while (pos != end) {
    const std::string_view line = next_line(pos, end);
    ++line_number;
    if (line.starts_with('#')) {
      if (line.find('\r') != std::string_view::npos) {
        fail(file, line_number, "carriage return inside a comment line");
      }
      std::string_view text = line.substr(1);
      if (text.starts_with(' ')) text.remove_prefix(1);
      recording.comments.emplace_back(text);
      continue;
    }
    if (is_blank(line)) {
      if (rest_is_blank(pos, end)) break;
      fail(file, line_number, "blank line before the header");
    }
    header = line;
    break;
  }
  if (header.empty()) throw RecordingError(file + ": no header row (only comment lines)");

  const std::size_t header_line = line_number;
  const std::vector<std::string> names = parse_header(header, file, header_line);
  check_required(names, options, file, header_line);
  const std::size_t cols = names.size();
  const auto time_it = std::find(names.begin(), names.end(), kTimeColumn);
  const bool has_time = time_it != names.end();
  const auto time_index = static_cast<std::size_t>(time_it - names.begin());

  // One line per row at most, plus a last line without '\n'.
  const auto max_rows = static_cast<std::size_t>(std::count(pos, end, '\n')) + 1;
  std::vector<std::vector<double>> columns(cols);
  for (auto& column : columns)
    column.reserve(max_rows);

  while (pos != end) {
    const std::string_view line = next_line(pos, end);
    ++line_number;
    if (is_blank(line)) {
      if (rest_is_blank(pos, end)) break;
      fail(file, line_number, "blank line between rows (only allowed at the end of the file)");
    }
    if (line.front() == '#') fail(file, line_number, "comment line after the header");

    const char* cell = line.data();
    const char* const line_end = line.data() + line.size();
    for (std::size_t j = 0; j < cols; ++j) {
      double value = 0.0;
      const auto [ptr, error] = std::from_chars(cell, line_end, value);
      const bool last = j + 1 == cols;
      // The cell must be a whole finite number followed by ',' (or the line's end if last).
      const bool ok = error == std::errc{} && std::isfinite(value) &&
                      (last ? ptr == line_end : ptr != line_end && *ptr == ',');
      if (!ok) explain_bad_row(line, names, file, line_number);
      columns[j].push_back(value);
      if (!last) cell = ptr + 1;
    }

    if (has_time) {
      const std::vector<double>& t = columns[time_index];
      if (t.size() > 1 && !(t[t.size() - 1] > t[t.size() - 2])) {
        fail(file, line_number, kTimeColumn,
             "not strictly increasing: " + format_number(t[t.size() - 1]) + " after " +
                 format_number(t[t.size() - 2]) + " on line " + std::to_string(line_number - 1));
      }
    }
  }
  if (columns.front().empty()) fail(file, header_line, "no data rows after the header");

  for (std::size_t j = 0; j < cols; ++j)
    recording.set_column(names[j], std::move(columns[j]));
  return recording;
}

// ---------------------------------------------------------------------------------------------
// Writer

namespace {

// The text is formatted into a buffer of this size and written whenever it fills: one buffer
// for the whole file (150 MB for 1e6 x 6) spends more time faulting in fresh pages than
// formatting, while 1 MiB stays in cache and still makes few, large writes.
constexpr std::size_t kWriteChunkBytes = std::size_t{1} << 20U;

// Refuses anything the reader would not read back the same, before the file is touched.
void check_writable(const Recording& recording, const std::string& file) {
  const std::vector<std::string>& names = recording.names();
  if (names.empty())
    throw RecordingError(file + ": nothing to write: the recording has no columns");
  for (const std::string& name : names) {
    if (is_blank(name) || name.find_first_of(",\r\n") != std::string::npos) {
      throw RecordingError(file + ": column " + quote_text(name) +
                           ": a column name must be non-blank and hold no ',' or line break");
    }
  }
  if (names.front().starts_with('#')) {
    throw RecordingError(file + ": column " + quote_text(names.front()) +
                         ": the first column name cannot start with '#' (it would read as a "
                         "comment)");
  }
  for (std::size_t i = 0; i < recording.comments.size(); ++i) {
    if (recording.comments[i].find_first_of("\r\n") != std::string::npos) {
      throw RecordingError(file + ": comment " + std::to_string(i + 1) +
                           " holds a line break; give each line its own comment");
    }
  }
  // Report the non-finite value that comes first in the file, as the reader would.
  const std::size_t header_line = recording.comments.size() + 1;
  std::size_t bad_row = recording.rows();
  std::size_t bad_col = 0;
  for (std::size_t j = 0; j < names.size(); ++j) {
    const std::span<const double> column = recording.column(j);
    const auto it = std::find_if(column.begin(), column.end(),
                                 [](double value) { return !std::isfinite(value); });
    const auto row = static_cast<std::size_t>(it - column.begin());
    if (row < bad_row) {
      bad_row = row;
      bad_col = j;
    }
  }
  if (bad_row < recording.rows()) {
    fail(file, header_line + bad_row + 1, names[bad_col],
         "cannot write " + format_number(recording.column(bad_col)[bad_row]) +
             ": recordings hold finite numbers only");
  }
}

}  // namespace

void write_recording_csv(const Recording& recording, const std::filesystem::path& path) {
  const std::string file = path.string();
  check_writable(recording, file);

  errno = 0;
  std::ofstream stream(path, std::ios::binary | std::ios::trunc);
  if (!stream) throw RecordingError(file + ": cannot open for writing: " + errno_text(errno));
  std::string out;
  out.reserve(kWriteChunkBytes + 1024);
  const auto flush = [&] {
    stream.write(out.data(), static_cast<std::streamsize>(out.size()));
    out.clear();
    if (!stream) throw RecordingError(file + ": cannot write: " + errno_text(errno));
  };

  for (const std::string& comment : recording.comments) {
    out += '#';
    if (!comment.empty()) (out += ' ') += comment;
    out += '\n';
    if (out.size() >= kWriteChunkBytes) flush();
  }
  const std::vector<std::string>& names = recording.names();
  const std::size_t cols = names.size();
  std::vector<std::span<const double>> columns;
  columns.reserve(cols);
  for (std::size_t j = 0; j < cols; ++j) {
    columns.push_back(recording.column(j));
    out += names[j];
    out += j + 1 == cols ? '\n' : ',';
    if (out.size() >= kWriteChunkBytes) flush();
  }

  const std::size_t rows = recording.rows();
  std::array<char, kMaxNumberChars + 8> cell{};
  for (std::size_t i = 0; i < rows; ++i) {
    for (std::size_t j = 0; j < cols; ++j) {
      char* const last =
          std::to_chars(cell.data(), cell.data() + kMaxNumberChars, columns[j][i]).ptr;
      *last = j + 1 == cols ? '\n' : ',';
      out.append(cell.data(), last + 1);
    }
    if (out.size() >= kWriteChunkBytes) flush();
  }
  flush();
  stream.close();
  if (!stream) throw RecordingError(file + ": cannot write: " + errno_text(errno));
}

}  // namespace selfsense::io
