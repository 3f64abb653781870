// The transducer geometry as YAML: the same five keys as a model file's `geometry:` section
// (model_yaml.hpp), at the top level of a file of its own (`selfsense identify --geometry`).
//
//   layer_thickness_m: 1.0e-4
//   electrode_area_m2: 2.5e-5
//   layers: 100
//   active_length_m: 1.0e-2
//   cross_section_m2: 2.5e-5
#pragma once

#include <filesystem>

#include "selfsense/models/geometry.hpp"

namespace selfsense::models {

// Strict; throws io::YamlError naming file, line and key.
[[nodiscard]] Geometry load_geometry(const std::filesystem::path& path);

}  // namespace selfsense::models
