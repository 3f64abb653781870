#include "selfsense/daemon/model_state_file.hpp"

#include <algorithm>
#include <cctype>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "selfsense/io/yaml_map.hpp"

namespace selfsense::daemon {

std::string_view to_string(StateOf of) noexcept {
  return of == StateOf::kAdapted ? "adapted" : "plain";
}

namespace {

void append_values(std::string& text, std::span<const double> values) {
  char number[32];
  for (std::size_t i = 0; i < values.size(); ++i) {
    static_cast<void>(std::snprintf(number, sizeof number, "%.17g", values[i]));
    text += (i == 0 ? "" : ", ") + std::string(number);
  }
}

void read_finite(io::YamlMap& root, const char* key, std::vector<double>& values) {
  root.read_sequence(key, values);
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i])) {
      root.fail(key, "value " + std::to_string(i) + " is not finite");
    }
  }
}

}  // namespace

void write_model_state(const std::filesystem::path& path, const models::SavedState& state,
                       StateOf of, std::span<const double> health) {
  for (const std::span<const double> values : {std::span<const double>(state.values), health}) {
    for (const double v : values) {
      if (!std::isfinite(v))
        throw std::runtime_error(path.string() + ": a state value is not finite");
    }
  }
  std::string text = "selfsense_model_state: 1\nstructure: ";
  text += models::to_string(state.identity.structure);
  char hash[32];
  static_cast<void>(std::snprintf(hash, sizeof hash, "%016" PRIx64, state.identity.parameter_hash));
  text += std::string("\nparameter_hash: \"") + hash + "\"\nreconstruction: ";
  text += to_string(of);
  text += "\nvalues: [";
  append_values(text, state.values);
  text += "]\n";
  if (!health.empty()) {
    text += "health: [";
    append_values(text, health);
    text += "]\n";
  }
  text += "complete: true\n";
  std::filesystem::path temporary = path;
  temporary += ".tmp";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out << text;
    out.flush();
    if (!out) throw std::runtime_error(temporary.string() + ": cannot write the model state");
  }
  std::error_code ec;
  std::filesystem::rename(temporary, path, ec);
  if (ec)
    throw std::runtime_error(path.string() + ": cannot replace the model state: " + ec.message());
}

models::SavedState read_model_state(const std::filesystem::path& path, StateOf* of,
                                    std::vector<double>* health) {
  io::YamlMap root = io::YamlMap::load_file(path);
  if (root.required<int>("selfsense_model_state") != 1) {
    root.fail("selfsense_model_state", "unknown format (this version reads 1)");
  }
  if (root.last_key() != "complete" || !root.required<bool>("complete")) {
    root.fail("complete", "missing at the end: the file is cut (written while it was read?)");
  }
  models::SavedState state;
  const std::string structure = root.required<std::string>("structure");
  const auto parsed = models::parse_structure(structure);
  if (!parsed) root.fail("structure", "unknown structure '" + structure + "'");
  state.identity.structure = *parsed;
  const std::string hash = root.required<std::string>("parameter_hash");
  if (hash.size() != 16 || !std::all_of(hash.begin(), hash.end(), [](char c) {
        return std::isxdigit(static_cast<unsigned char>(c)) != 0;
      })) {
    root.fail("parameter_hash", "expected 16 hexadecimal digits");
  }
  state.identity.parameter_hash = std::stoull(hash, nullptr, 16);
  std::string kind = "plain";
  root.read("reconstruction", kind);
  if (kind != "plain" && kind != "adapted") {
    root.fail("reconstruction", "'" + kind + "' is not one of plain, adapted");
  }
  if (of != nullptr) *of = kind == "adapted" ? StateOf::kAdapted : StateOf::kPlain;
  if (!root.has("values")) root.fail("values", "missing");
  read_finite(root, "values", state.values);
  state.identity.state_size = state.values.size();
  std::vector<double> health_values;
  if (root.has("health")) read_finite(root, "health", health_values);
  if (health != nullptr) *health = std::move(health_values);
  root.finish();
  return state;
}

}  // namespace selfsense::daemon
