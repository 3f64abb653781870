#include "selfsense/model_io/geometry_yaml.hpp"

#include <string>

#include "geometry_fields.hpp"
#include "selfsense/io/yaml_map.hpp"

namespace selfsense::models {

Geometry read_geometry_fields(io::YamlMap& map) {
  Geometry geo;
  geo.layer_thickness = map.required<double>("layer_thickness_m");
  geo.electrode_area = map.required<double>("electrode_area_m2");
  geo.layers = map.required<double>("layers");
  geo.active_length = map.required<double>("active_length_m");
  geo.cross_section = map.required<double>("cross_section_m2");
  map.finish();
  return geo;
}

Geometry load_geometry(const std::filesystem::path& path) {
  io::YamlMap g = io::YamlMap::load_file(path);
  const Geometry geo = read_geometry_fields(g);
  // is_valid names "geometry.KEY"; in a file of its own the key stands at the top level.
  std::string why;
  if (!geo.is_valid(&why)) throw io::YamlError(g.locate(why.substr(why.find('.') + 1)));
  return geo;
}

}  // namespace selfsense::models
