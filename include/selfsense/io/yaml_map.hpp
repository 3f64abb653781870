// Strict reading of YAML configuration files: a view over one mapping node that knows its key
// path ("plant.creep.tau_s[2]"), hands out typed values, and at finish() rejects every key that
// nobody asked for. Every error is a YamlError whose message starts with "file:line: key.path: "
// and is one line: line breaks and other control bytes of keys, values and the YAML parser's
// messages are escapes ("\n", "\x1b"); echoed values are cut to 64 characters.
//
// Typical use with plain config structs that carry their defaults in-class:
//   YamlMap root = YamlMap::load_file("P.yaml");
//   YamlMap plant = root.map("plant");
//   plant.read("sample_rate_hz", config.sample_rate_hz);  // optional, keeps the default
//   ...
//   plant.finish();  // unknown keys are errors
//   root.finish();
// Not real-time code: it allocates and throws.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace selfsense::io {

class YamlError final : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Conversions of one scalar node; each throws YamlError naming `where` on a type mismatch.
void from_yaml(const YAML::Node& node, const std::string& where, double& out);
void from_yaml(const YAML::Node& node, const std::string& where, int& out);
void from_yaml(const YAML::Node& node, const std::string& where, std::int64_t& out);
void from_yaml(const YAML::Node& node, const std::string& where, std::uint64_t& out);
// std::size_t on 32-bit targets (armhf), where it is not std::uint64_t; values above its range
// are refused.
void from_yaml(const YAML::Node& node, const std::string& where, unsigned int& out);
void from_yaml(const YAML::Node& node, const std::string& where, bool& out);
void from_yaml(const YAML::Node& node, const std::string& where, std::string& out);

class YamlMap final {
 public:
  // The document's root must be a mapping. Throws YamlError on a parse error or a missing file.
  [[nodiscard]] static YamlMap load_file(const std::filesystem::path& path);
  [[nodiscard]] static YamlMap from_string(const std::string& text,
                                           const std::string& source = "<string>");

  [[nodiscard]] bool has(std::string_view key) const;
  // Full key path of a key in this map, e.g. "plant.mechanics.resonance_hz".
  [[nodiscard]] std::string path(std::string_view key) const;

  template <typename T>
  [[nodiscard]] T required(std::string_view key) {
    T value{};
    const YAML::Node node = take(key, true);
    from_yaml(node, where(key, node), value);
    return value;
  }
  template <typename T>
  [[nodiscard]] T optional(std::string_view key, T fallback) {
    read(key, fallback);
    return fallback;
  }
  // Reads the key into `value` if present; keeps `value` (the default) otherwise.
  template <typename T>
  void read(std::string_view key, T& value) {
    const YAML::Node node = take(key, false);
    if (node) from_yaml(node, where(key, node), value);
  }
  // Reads a sequence of scalars into `values` if present (replacing them).
  template <typename T>
  void read_sequence(std::string_view key, std::vector<T>& values) {
    const YAML::Node node = take(key, false);
    if (!node) return;
    if (!node.IsSequence()) fail_at(node, path(key), "expected a sequence");
    std::vector<T> out(node.size());
    for (std::size_t i = 0; i < node.size(); ++i) {
      const YAML::Node item = node[i];
      from_yaml(item, where_item(key, i, item), out[i]);
    }
    values = std::move(out);
  }

  // Nested mapping; required, or empty when absent.
  [[nodiscard]] YamlMap map(std::string_view key);
  [[nodiscard]] std::optional<YamlMap> optional_map(std::string_view key);
  // A sequence of mappings (key[0], key[1], ...); empty when absent.
  [[nodiscard]] std::vector<YamlMap> maps(std::string_view key);

  // Throws YamlError naming every key of this map that was never read.
  void finish() const;
  // Throws YamlError "file:line: path.key: message" at the key (or the map if absent).
  [[noreturn]] void fail(std::string_view key, const std::string& message) const;

  // Prefixes "file:line: " to a message that starts with a key path read through any map of this
  // document ("plant.mechanics.resonance_hz: ..."), for validation errors found after loading.
  // A key path in no line of the file (a default) takes the line of another key path the message
  // names, else line 1. The result is one line, like every error.
  [[nodiscard]] std::string locate(const std::string& message) const;
  [[nodiscard]] const std::string& source() const noexcept { return context_->source; }
  // Every key path a reader of this document asked for, whether the file has it or not: the
  // keys the strict reading knows ("loop.rate_hz", "control.filters[0].type", ...).
  [[nodiscard]] const std::set<std::string, std::less<>>& known_keys() const noexcept {
    return context_->known;
  }
  // The mapping's last key in the document's order (empty for an empty mapping).
  [[nodiscard]] std::string last_key() const;
  // The mapping as YAML text, comments and layout dropped: two readings compare equal when
  // their content is the same.
  [[nodiscard]] std::string canonical_text() const;

 private:
  struct Context {
    std::string source{};
    std::map<std::string, int, std::less<>> lines{};  // key path -> 1-based line
    std::set<std::string, std::less<>> known{};       // every key path asked for
  };
  YamlMap(const YAML::Node& node, std::string path, std::shared_ptr<Context> context);
  YAML::Node take(std::string_view key, bool required);
  [[nodiscard]] std::string where(std::string_view key, const YAML::Node& node) const;
  [[nodiscard]] std::string where_item(std::string_view key, std::size_t index,
                                       const YAML::Node& node) const;
  [[noreturn]] void fail_at(const YAML::Node& node, const std::string& path,
                            const std::string& message) const;

  YAML::Node node_;
  std::string path_;
  std::shared_ptr<Context> context_;
  std::set<std::string, std::less<>> consumed_{};
};

}  // namespace selfsense::io
