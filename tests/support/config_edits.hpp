// The shipped daemon configurations (config/*.yaml) with edits, for the tests of what the loader
// says of a changed file. The edited copy is written into a scratch directory (never into the
// source tree) beside links to config/models and config/plant, so that the example's paths,
// relative to its file, resolve as they do for the shipped one.
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "selfsense/daemon/config.hpp"
#include "support/scratch_dir.hpp"

namespace selfsense::test {

// (from, to): the first occurrence of `from` becomes `to`.
using Edits = std::vector<std::pair<std::string, std::string>>;

inline std::filesystem::path shipped_config_dir() {
  return std::filesystem::path(SELFSENSE_SOURCE_DIR) / "config";
}

// `text` with the edits applied in order; throws naming a `from` that does not occur, so that a
// changed example fails the test loudly instead of testing the unedited file.
inline std::string edited(std::string text, const Edits& edits, std::string_view what) {
  for (const auto& [from, to] : edits) {
    const std::size_t at = text.find(from);
    if (at == std::string::npos) {
      throw std::runtime_error(std::string(what) + " has no '" + from + "'");
    }
    text.replace(at, from.size(), to);
  }
  return text;
}

// config/SHIPPED with `edits`, written as FILE (default: SHIPPED) into a scratch directory that
// links models/ and plant/ to config/'s, and loaded with `reader` (the driver registry). The
// problems name FILE, so a test can look for it.
inline daemon::ConfigResult load_shipped_with(std::string_view shipped, const Edits& edits,
                                              daemon::DriverSectionReader& reader,
                                              std::string file = {}) {
  const ScratchDir dir("config");
  for (const char* linked : {"models", "plant"}) {
    std::filesystem::create_directory_symlink(shipped_config_dir() / linked, dir.path() / linked);
  }
  if (file.empty()) file = shipped;
  const std::string name = "config/" + std::string(shipped);
  const std::filesystem::path path = dir.path() / file;
  write_text(path, edited(read_text(shipped_config_dir() / shipped), edits, name));
  return daemon::load_config(path, &reader);
}

}  // namespace selfsense::test
