// Parameter validation shared by the control laws.
//
// Control laws validate their parameters when they are constructed (never in step()) and reject
// a bad set with a ParameterError whose message names the parameter and the violated
// constraint: "Pid.output_max: -1 must be > Pid.output_min = 0". Each Params/Config struct also
// has a non-throwing `bool is_valid(..., std::string* why) const` for configuration loaders that
// collect every problem. The library depends on the standard library and the ground floor
// (selfsense::base) only, so it keeps its own small copy of the checks instead of linking
// selfsense::operators.
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>

namespace selfsense::control {

class ParameterError final : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// Throws ParameterError(why) when `valid` is false.
void require_valid(bool valid, const std::string& why);

namespace check {

// Each returns false and writes "<name>: <value> must ..." to *why (if non-null) on failure.
bool finite(std::string_view name, double value, std::string* why);
bool positive(std::string_view name, double value, std::string* why);
bool non_negative(std::string_view name, double value, std::string* why);
// value < limit; `limit_text` says where the limit comes from ("0.45 * sample rate").
bool below(std::string_view name, double value, double limit, std::string_view limit_text,
           std::string* why);
// Writes "<name>: <message>" and returns false: for constraints the helpers above do not cover.
bool fail(std::string_view name, std::string_view message, std::string* why);

}  // namespace check
}  // namespace selfsense::control
