// What every fuzz target shares: a property check that aborts (so libFuzzer, or the replay
// driver, reports the input), checks that an error message names where the problem is, and a
// scratch file for the parsers that read from a path. Test code only.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>

namespace selfsense::fuzz {

// Prints the property and the detail to stderr and aborts.
[[noreturn]] void violated(std::string_view property, std::string_view detail);

inline void require(bool ok, std::string_view property, std::string_view detail = {}) {
  if (!ok) violated(property, detail);
}

// True when `message` starts with "<file>:<line>: " and line >= 1.
[[nodiscard]] bool names_file_and_line(std::string_view message, std::string_view file);

// True when `message` starts with "<file>:<line>: <key path>: " (a YamlMap error or a located
// problem): the key path is non-empty and holds no blank.
[[nodiscard]] bool names_file_line_and_key(std::string_view message, std::string_view file);

// The fuzz input as text (any bytes, NUL included).
[[nodiscard]] inline std::string as_text(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};  // NOLINT(*-reinterpret-cast)
}

// Hands out the input's bytes as values, front to back; zeros once the bytes run out.
class ByteReader final {
 public:
  ByteReader(const std::uint8_t* data, std::size_t size) noexcept : bytes_(data, size) {}

  [[nodiscard]] std::uint8_t byte() noexcept {
    if (bytes_.empty()) return 0;
    const std::uint8_t b = bytes_.front();
    bytes_ = bytes_.subspan(1);
    return b;
  }
  [[nodiscard]] std::uint16_t u16() noexcept {
    const auto high = static_cast<unsigned>(byte());
    return static_cast<std::uint16_t>((high << 8U) | byte());
  }
  [[nodiscard]] std::uint64_t u64() noexcept {
    std::uint64_t v = 0;
    for (int i = 0; i < 8; ++i)
      v = (v << 8U) | byte();
    return v;
  }
  // One entry of a table, chosen by the next byte.
  template <typename T, std::size_t N>
  [[nodiscard]] T pick(const T (&table)[N]) noexcept {  // NOLINT(*-avoid-c-arrays)
    return table[byte() % N];                           // NOLINT(*-constant-array-index)
  }
  [[nodiscard]] std::span<const std::uint8_t> rest() const noexcept { return bytes_; }

 private:
  std::span<const std::uint8_t> bytes_;
};

// A file in a private directory of this process (removed at exit), rewritten by every input.
class ScratchFile final {
 public:
  // `name` is the file's name inside the directory ("in.csv").
  explicit ScratchFile(std::string_view name);
  ~ScratchFile();
  ScratchFile(const ScratchFile&) = delete;
  ScratchFile& operator=(const ScratchFile&) = delete;
  ScratchFile(ScratchFile&&) = delete;
  ScratchFile& operator=(ScratchFile&&) = delete;

  // Replaces the content; aborts if the file cannot be written (not a finding of the parser).
  void write(std::string_view content) const;
  [[nodiscard]] const std::filesystem::path& path() const noexcept { return path_; }
  [[nodiscard]] const std::filesystem::path& directory() const noexcept { return directory_; }

 private:
  std::filesystem::path directory_{};
  std::filesystem::path path_{};
};

}  // namespace selfsense::fuzz
