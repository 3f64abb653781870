#include "fuzz_check.hpp"

#include <unistd.h>

#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <system_error>
#include <vector>

namespace selfsense::fuzz {

void violated(std::string_view property, std::string_view detail) {
  static_cast<void>(std::fprintf(stderr, "\nfuzz property violated: %.*s\n  %.*s\n",
                                 static_cast<int>(property.size()), property.data(),
                                 static_cast<int>(detail.size()), detail.data()));
  std::abort();
}

namespace {

// Length of "<file>:<line>: " at the start of message, or 0 when it is not there.
std::size_t file_line_prefix(std::string_view message, std::string_view file) {
  if (!message.starts_with(file) || message.size() <= file.size() || message[file.size()] != ':') {
    return 0;
  }
  std::size_t pos = file.size() + 1;
  const std::size_t digits_start = pos;
  while (pos < message.size() && std::isdigit(static_cast<unsigned char>(message[pos])) != 0)
    ++pos;
  if (pos == digits_start || message.substr(digits_start, pos - digits_start) == "0") return 0;
  if (message.substr(pos, 2) != ": ") return 0;
  return pos + 2;
}

}  // namespace

bool names_file_and_line(std::string_view message, std::string_view file) {
  return file_line_prefix(message, file) != 0;
}

bool names_file_line_and_key(std::string_view message, std::string_view file) {
  const std::size_t start = file_line_prefix(message, file);
  if (start == 0) return false;
  const std::size_t end = message.find(": ", start);
  if (end == std::string_view::npos || end == start) return false;
  const std::string_view key = message.substr(start, end - start);
  return key.find_first_of(" \t\n") == std::string_view::npos;
}

ScratchFile::ScratchFile(std::string_view name) {
  std::error_code error;
  const std::filesystem::path base = std::filesystem::temp_directory_path(error);
  std::string pattern = (error ? std::filesystem::path("/tmp") : base) / "selfsense-fuzz-XXXXXX";
  std::vector<char> buffer(pattern.begin(), pattern.end());
  buffer.push_back('\0');
  if (::mkdtemp(buffer.data()) == nullptr) violated("scratch directory", pattern);
  directory_ = buffer.data();
  path_ = directory_ / name;
}

ScratchFile::~ScratchFile() {
  std::error_code ignored;
  std::filesystem::remove_all(directory_, ignored);
}

void ScratchFile::write(std::string_view content) const {
  std::ofstream out(path_, std::ios::binary | std::ios::trunc);
  out.write(content.data(), static_cast<std::streamsize>(content.size()));
  out.close();
  if (!out) violated("scratch file", path_.string());
}

}  // namespace selfsense::fuzz
