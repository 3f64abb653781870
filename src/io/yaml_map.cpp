#include "selfsense/io/yaml_map.hpp"

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <system_error>
#include <utility>

namespace selfsense::io {

namespace {

// Echoed scalars are cut so that a runaway value cannot flood the terminal.
constexpr std::size_t kMaxEchoChars = 64;

// Every message is one line (check-config prints one problem per line): line breaks, tabs and
// other control bytes that a file may carry in keys, values or yaml-cpp's own messages are
// written as escapes.
std::string one_line(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (c == '\n') {
      out += "\\n";
    } else if (c == '\r') {
      out += "\\r";
    } else if (c == '\t') {
      out += "\\t";
    } else if (byte < 0x20U || byte == 0x7fU) {
      constexpr std::string_view kHex = "0123456789abcdef";
      out += "\\x";
      out += kHex[byte >> 4U];
      out += kHex[byte & 0xfU];
    } else {
      out += c;
    }
  }
  return out;
}

[[noreturn]] void raise(const std::string& message) {
  throw YamlError{one_line(message)};
}

int line_of(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  return mark.line >= 0 ? mark.line + 1 : 0;
}

std::string describe(const YAML::Node& node) {
  if (node.IsNull()) return "null";
  if (node.IsSequence()) return "a sequence";
  if (node.IsMap()) return "a mapping";
  const std::string& scalar = node.Scalar();
  if (scalar.size() <= kMaxEchoChars) return "'" + scalar + "'";
  return "'" + scalar.substr(0, kMaxEchoChars) + "...'";
}

// `where` is "file:line: path".
[[noreturn]] void type_error(const YAML::Node& node, const std::string& where,
                             const std::string& expected) {
  raise(where + ": expected " + expected + ", got " + describe(node));
}

template <typename T>
void convert(const YAML::Node& node, const std::string& where, const std::string& expected,
             T& out) {
  if (!node.IsScalar()) type_error(node, where, expected);
  try {
    out = node.as<T>();
  } catch (const YAML::Exception&) {
    type_error(node, where, expected);
  }
}

}  // namespace

void from_yaml(const YAML::Node& node, const std::string& where, double& out) {
  convert(node, where, "a number", out);
  if (!std::isfinite(out)) type_error(node, where, "a finite number");
}
void from_yaml(const YAML::Node& node, const std::string& where, int& out) {
  convert(node, where, "an integer", out);
}
void from_yaml(const YAML::Node& node, const std::string& where, std::int64_t& out) {
  convert(node, where, "an integer", out);
}
void from_yaml(const YAML::Node& node, const std::string& where, std::uint64_t& out) {
  if (node.IsScalar() && !node.Scalar().empty() && node.Scalar().front() == '-') {
    type_error(node, where, "a non-negative integer");
  }
  convert(node, where, "a non-negative integer", out);
}
void from_yaml(const YAML::Node& node, const std::string& where, unsigned int& out) {
  std::uint64_t wide = 0;
  from_yaml(node, where, wide);
  if (wide > std::numeric_limits<unsigned int>::max()) {
    type_error(
        node, where,
        "a non-negative integer up to " + std::to_string(std::numeric_limits<unsigned int>::max()));
  }
  out = static_cast<unsigned int>(wide);
}
void from_yaml(const YAML::Node& node, const std::string& where, bool& out) {
  convert(node, where, "true or false", out);
}
void from_yaml(const YAML::Node& node, const std::string& where, std::string& out) {
  convert(node, where, "a string", out);
}

YamlMap::YamlMap(const YAML::Node& node, std::string path, std::shared_ptr<Context> context)
    : node_{node}, path_{std::move(path)}, context_{std::move(context)} {}

YamlMap YamlMap::from_string(const std::string& text, const std::string& source) {
  auto context = std::make_shared<Context>();
  context->source = source;
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    raise(source + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  if (!root.IsMap()) {
    raise(source + ":1: the document must be a mapping of keys to values");
  }
  return YamlMap{root, "", context};
}

YamlMap YamlMap::load_file(const std::filesystem::path& path) {
  // Only a regular file is read: yaml-cpp given a directory (an ifstream that opens but cannot be
  // read) leaks its stream buffer, and "cannot open" is the clearer message anyway.
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) {
    raise(path.string() + (std::filesystem::exists(path, error) ? ": not a regular file"
                                                                : ": cannot open the file"));
  }
  std::ifstream in{path, std::ios::binary};
  std::ostringstream text;
  text << in.rdbuf();
  if (!in || in.bad()) raise(path.string() + ": cannot read the file");
  return from_string(text.str(), path.string());
}

std::string YamlMap::path(std::string_view key) const {
  return path_.empty() ? std::string{key} : path_ + "." + std::string{key};
}

bool YamlMap::has(std::string_view key) const {
  for (const auto& pair : node_) {
    if (pair.first.Scalar() == key) return true;
  }
  return false;
}

YAML::Node YamlMap::take(std::string_view key, bool required) {
  context_->known.insert(path(key));
  for (const auto& pair : node_) {
    if (pair.first.Scalar() != key) continue;
    consumed_.emplace(key);
    context_->lines.emplace(path(key), line_of(pair.first));
    return pair.second;
  }
  if (required) fail(key, "required key is missing");
  return YAML::Node{YAML::NodeType::Undefined};
}

std::string YamlMap::where(std::string_view key, const YAML::Node& node) const {
  return context_->source + ":" + std::to_string(line_of(node)) + ": " + path(key);
}

std::string YamlMap::where_item(std::string_view key, std::size_t index,
                                const YAML::Node& node) const {
  const std::string item = path(key) + "[" + std::to_string(index) + "]";
  context_->lines.emplace(item, line_of(node));
  return context_->source + ":" + std::to_string(line_of(node)) + ": " + item;
}

void YamlMap::fail_at(const YAML::Node& node, const std::string& path,
                      const std::string& message) const {
  raise(context_->source + ":" + std::to_string(line_of(node)) + ": " + path + ": " + message);
}

void YamlMap::fail(std::string_view key, const std::string& message) const {
  for (const auto& pair : node_) {
    if (pair.first.Scalar() == key) fail_at(pair.first, path(key), message);
  }
  fail_at(node_, path(key), message);
}

YamlMap YamlMap::map(std::string_view key) {
  const YAML::Node node = take(key, true);
  if (!node.IsMap()) fail_at(node, path(key), "expected a mapping, got " + describe(node));
  return YamlMap{node, path(key), context_};
}

std::optional<YamlMap> YamlMap::optional_map(std::string_view key) {
  const YAML::Node node = take(key, false);
  if (!node) return std::nullopt;
  if (!node.IsMap()) fail_at(node, path(key), "expected a mapping, got " + describe(node));
  return YamlMap{node, path(key), context_};
}

std::vector<YamlMap> YamlMap::maps(std::string_view key) {
  const YAML::Node node = take(key, false);
  std::vector<YamlMap> out;
  if (!node) return out;
  if (!node.IsSequence()) fail_at(node, path(key), "expected a sequence, got " + describe(node));
  for (std::size_t i = 0; i < node.size(); ++i) {
    const YAML::Node item = node[i];
    const std::string item_path = path(key) + "[" + std::to_string(i) + "]";
    if (!item.IsMap()) fail_at(item, item_path, "expected a mapping, got " + describe(item));
    context_->lines.emplace(item_path, line_of(item));
    out.push_back(YamlMap{item, item_path, context_});
  }
  return out;
}

std::string YamlMap::last_key() const {
  std::string last;
  for (const auto& pair : node_)
    last = pair.first.Scalar();
  return last;
}

std::string YamlMap::canonical_text() const {
  return YAML::Dump(node_);
}

void YamlMap::finish() const {
  std::set<std::string, std::less<>> seen;
  for (const auto& pair : node_) {
    const std::string& key = pair.first.Scalar();
    if (!seen.insert(key).second) fail_at(pair.first, path(key), "duplicate key");
    if (!consumed_.contains(key)) fail_at(pair.first, path(key), "unknown key");
  }
}

std::string YamlMap::locate(const std::string& message) const {
  // The longest recorded key path that the message starts with, followed by ':' or '['.
  std::string best;
  int line = 0;
  for (const auto& [key, key_line] : context_->lines) {
    if (message.size() > key.size() && message.compare(0, key.size(), key) == 0 &&
        (message[key.size()] == ':' || message[key.size()] == '[' || message[key.size()] == '.') &&
        key.size() > best.size()) {
      best = key;
      line = key_line;
    }
  }
  if (best.empty()) {
    // A key left at its default stands on no line: name the line of another key the message
    // names ("... must be inside control.command_v_per_m"), else the document's first line.
    line = 1;
    const auto boundary = [&](std::size_t at) {
      return at >= message.size() ||
             std::string_view(" :[.,;)'").find(message[at]) != std::string_view::npos;
    };
    for (const auto& [key, key_line] : context_->lines) {
      for (auto at = message.find(key); at != std::string::npos; at = message.find(key, at + 1)) {
        if (at > 0 && message[at - 1] == ' ' && boundary(at + key.size()) &&
            key.size() > best.size()) {
          best = key;
          line = key_line;
        }
      }
    }
  }
  return one_line(context_->source + ":" + std::to_string(line) + ": " + message);
}

}  // namespace selfsense::io
