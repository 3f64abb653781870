// The geometry's five keys read from a YAML mapping (a model file's `geometry:` section or a
// geometry file), unchecked; the caller validates and names where.
#pragma once

#include "selfsense/io/yaml_map.hpp"
#include "selfsense/models/geometry.hpp"

namespace selfsense::models {

[[nodiscard]] Geometry read_geometry_fields(io::YamlMap& map);

}  // namespace selfsense::models
