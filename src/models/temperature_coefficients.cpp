#include "selfsense/models/temperature_coefficients.hpp"

#include <cmath>

namespace selfsense::models {

bool TemperatureCoefficients::is_valid(const std::string& prefix, std::string* why) const {
  const auto bad = [&](const std::string& key) {
    if (why != nullptr) *why = prefix + key + ": must be finite";
    return false;
  };
  if (!std::isfinite(reference_degc)) return bad("reference_degc");
  const struct {
    const char* name;
    const SideTemperature* side;
  } sides[] = {{"sensor", &sensor}, {"actuator", &actuator}};
  for (const auto& s : sides) {
    const struct {
      const char* name;
      const TemperaturePolynomial* poly;
    } polys[] = {
        {"linear", &s.side->linear}, {"loop", &s.side->loop}, {"coupling", &s.side->coupling}};
    for (const auto& p : polys) {
      const std::string key = std::string(s.name) + "." + p.name;
      if (!std::isfinite(p.poly->per_k)) return bad(key + ".per_k");
      if (!std::isfinite(p.poly->per_k2)) return bad(key + ".per_k2");
    }
  }
  if (!std::isfinite(increments.linear_per_k)) return bad("increments.linear_per_k");
  if (!std::isfinite(increments.loop_per_k)) return bad("increments.loop_per_k");
  return true;
}

}  // namespace selfsense::models
