#include "selfsense/models/transducer_model.hpp"

#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>

#include "selfsense/operators/parameter_error.hpp"

namespace selfsense::models {
namespace {

constexpr std::array<std::pair<Structure, std::string_view>, 7> kNames{{
    {Structure::kLinear, "linear"},
    {Structure::kPermittivity, "permittivity"},
    {Structure::kChargeDrive, "charge-drive"},
    {Structure::kHysteresis, "hysteresis"},
    {Structure::kHysteresisCreep, "hysteresis-creep"},
    {Structure::kPreisachCreep, "preisach-creep"},
    {Structure::kStressHysteresis, "stress-hysteresis"},
}};

bool side_valid(const char* name, const std::optional<SideModel>& side, double ts,
                std::string* why) {
  if (!side) return true;
  std::string inner;
  if (!side->op.is_valid(&inner)) {
    if (why != nullptr) *why = std::string(name) + "." + inner;
    return false;
  }
  if (side->sample_time != ts) {
    if (why != nullptr) *why = std::string(name) + ".sample_time differs from sample_time";
    return false;
  }
  for (const double g : side->linear_gains) {
    if (!operators::check::finite(std::string(name) + ".coupling", g, why)) return false;
  }
  return operators::check::finite(std::string(name) + ".offset", side->offset, why) &&
         operators::check::finite(std::string(name) + ".quadratic", side->quadratic, why);
}

bool range_valid(const char* name, const std::optional<InputRange>& range, std::string* why) {
  if (!range) return true;
  if (std::isfinite(range->min) && std::isfinite(range->max) && range->max > range->min) {
    return true;
  }
  if (why != nullptr) *why = std::string(name) + ": expected finite [min, max] with min < max";
  return false;
}

}  // namespace

std::string_view to_string(Structure s) noexcept {
  for (const auto& [structure, name] : kNames) {
    if (structure == s) return name;
  }
  return "unknown";
}

std::optional<Structure> parse_structure(std::string_view name) noexcept {
  for (const auto& [structure, n] : kNames) {
    if (n == name) return structure;
  }
  return std::nullopt;
}

std::string structure_names() {
  std::string out;
  for (const auto& [structure, name] : kNames) {
    if (!out.empty()) out += ", ";
    out += name;
  }
  return out;
}

Drive drive_of(Structure s) noexcept {
  return s == Structure::kChargeDrive ? Drive::kCharge : Drive::kField;
}

bool TransducerModel::is_valid(std::string* why) const {
  if (!operators::check::positive("sample_time", sample_time, why)) return false;
  if (sensed_correction && !sensed_correction->is_valid("corrections.sensed", why)) return false;
  if (strain_correction && !strain_correction->is_valid("corrections.strain", why)) return false;
  if (temperature && !temperature->is_valid("temperature.", why)) return false;
  if (!range_valid("input_range.drive", drive_range, why) ||
      !range_valid("input_range.sensed", sensed_range, why)) {
    return false;
  }
  if (structure == Structure::kStressHysteresis) {
    if (!vectorial || (!vectorial->sensor && !vectorial->actuator)) {
      if (why != nullptr) *why = "model: stress-hysteresis needs its vectorial section";
      return false;
    }
    // Plain sides complete the vectorial model where it has none (stress_sides.hpp).
    for (const auto& [name, plain, stressed] :
         {std::tuple{"sensor", sensor.has_value(), vectorial->sensor.has_value()},
          std::tuple{"actuator", actuator.has_value(), vectorial->actuator.has_value()}}) {
      if (plain && stressed) {
        if (why != nullptr) {
          *why = std::string(name) +
                 ": the vectorial section has this side already (a plain side only completes it)";
        }
        return false;
      }
    }
    return vectorial->is_valid(why) && side_valid("sensor", sensor, sample_time, why) &&
           side_valid("actuator", actuator, sample_time, why);
  }
  if (!sensor && !actuator) {
    if (why != nullptr) *why = "model: needs a sensor or an actuator side";
    return false;
  }
  if (geometry && !geometry->is_valid(why)) return false;
  return side_valid("sensor", sensor, sample_time, why) &&
         side_valid("actuator", actuator, sample_time, why);
}

bool can_reconstruct(const TransducerModel& model) noexcept {
  if (model.vectorial && model.vectorial->sensor) return true;
  return model.sensor && !model.sensor->linear_gains.empty() &&
         model.sensor->linear_gains.front() != 0.0;
}

}  // namespace selfsense::models
