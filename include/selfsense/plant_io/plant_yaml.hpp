// Loading a plant configuration file (target selfsense_plant_io): the `plant:` section maps one
// to one onto PlantConfig (config.hpp), the optional `excitation:` section onto
// ExcitationConfig (excitation.hpp). Strict: unknown keys, wrong types and invalid values throw
// io::YamlError naming file, line and key path. Not real-time code.
#pragma once

#include <filesystem>
#include <string>

#include "selfsense/plant/config.hpp"
#include "selfsense/plant/excitation.hpp"

namespace selfsense::plant {

struct PlantFile {
  PlantConfig plant{};
  ExcitationConfig excitation{};
};

[[nodiscard]] PlantFile load_plant_file(const std::filesystem::path& path);
[[nodiscard]] PlantFile parse_plant_yaml(const std::string& text,
                                         const std::string& source = "<string>");

}  // namespace selfsense::plant
