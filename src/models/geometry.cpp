#include "selfsense/models/geometry.hpp"

#include "selfsense/operators/parameter_error.hpp"

namespace selfsense::models {

bool Geometry::is_valid(std::string* why) const {
  namespace check = operators::check;
  if (!check::positive("geometry.layer_thickness", layer_thickness, why) ||
      !check::positive("geometry.electrode_area", electrode_area, why) ||
      !check::positive("geometry.active_length", active_length, why) ||
      !check::positive("geometry.cross_section", cross_section, why) ||
      !check::finite("geometry.layers", layers, why)) {
    return false;
  }
  if (layers < 1.0) {
    if (why != nullptr)
      *why = "geometry.layers: " + operators::format_number(layers) + " must be >= 1";
    return false;
  }
  return true;
}

}  // namespace selfsense::models
