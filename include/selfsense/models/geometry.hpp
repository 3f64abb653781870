// Transducer geometry: converts terminal quantities to the field quantities the models use.
//
//   E = u / h               u: voltage [V], h: layer thickness [m]
//   D = q / (A * n)         q: charge [C], A: electrode area of one layer [m^2], n: layers
//   S = x / L               x: displacement [m], L: active length [m]
//   T = F / A_mech          F: force [N] (compression < 0), A_mech: mechanical cross-section [m^2]
// and back. Not on the real-time path only because nothing there needs it; all are O(1).
#pragma once

#include <string>

namespace selfsense::models {

struct Geometry {
  double layer_thickness{0.0};  // h [m]
  double electrode_area{0.0};   // A [m^2], one layer
  double layers{1.0};           // n
  double active_length{0.0};    // L [m]
  double cross_section{0.0};    // A_mech [m^2]

  // Every field finite and > 0 (layers >= 1); names the field ("geometry.layer_thickness").
  [[nodiscard]] bool is_valid(std::string* why) const;

  [[nodiscard]] double field(double voltage) const noexcept { return voltage / layer_thickness; }
  [[nodiscard]] double displacement_density(double charge) const noexcept {
    return charge / (electrode_area * layers);
  }
  [[nodiscard]] double strain(double displacement) const noexcept {
    return displacement / active_length;
  }
  [[nodiscard]] double stress(double force) const noexcept { return force / cross_section; }

  [[nodiscard]] double voltage(double e) const noexcept { return e * layer_thickness; }
  [[nodiscard]] double charge(double d) const noexcept { return d * electrode_area * layers; }
  [[nodiscard]] double displacement(double s) const noexcept { return s * active_length; }
  [[nodiscard]] double force(double t) const noexcept { return t * cross_section; }
};

}  // namespace selfsense::models
