#include "selfsense/control/parameter_error.hpp"

#include <cmath>

#include "selfsense/base/format_number.hpp"

namespace selfsense::control {

void require_valid(bool valid, const std::string& why) {
  if (!valid) throw ParameterError(why);
}

namespace check {
namespace {

bool describe(std::string_view name, double value, std::string_view constraint, std::string* why) {
  if (why != nullptr)
    *why = std::string(name) + ": " + base::format_number(value) + ' ' + std::string(constraint);
  return false;
}

}  // namespace

bool finite(std::string_view name, double value, std::string* why) {
  return std::isfinite(value) || describe(name, value, "must be finite", why);
}

bool positive(std::string_view name, double value, std::string* why) {
  return finite(name, value, why) && (value > 0.0 || describe(name, value, "must be > 0", why));
}

bool non_negative(std::string_view name, double value, std::string* why) {
  return finite(name, value, why) && (value >= 0.0 || describe(name, value, "must be >= 0", why));
}

bool below(std::string_view name, double value, double limit, std::string_view limit_text,
           std::string* why) {
  if (!finite(name, value, why)) return false;
  if (value < limit) return true;
  return describe(name, value,
                  "must be < " + std::string(limit_text) + " = " + base::format_number(limit), why);
}

bool fail(std::string_view name, std::string_view message, std::string* why) {
  if (why != nullptr) *why = std::string(name) + ": " + std::string(message);
  return false;
}

}  // namespace check
}  // namespace selfsense::control
