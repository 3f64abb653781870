// Parameter validation shared by the control laws.
//
// Control laws validate their parameters when they are constructed (never in step()) and reject
// a bad set with a ParameterError whose message names the parameter and the violated
// constraint: "Pid.output_max: -1 must be > Pid.output_min = 0". Each Params/Config struct also
// has a non-throwing `bool is_valid(..., std::string* why) const` for configuration loaders that
// collect every problem. The checks are the ground floor's (selfsense/base/check.hpp), the same
// vocabulary and message format as the operators' and the plant's.
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>

#include "selfsense/base/check.hpp"

namespace selfsense::control {

class ParameterError final : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// Throws ParameterError(why) when `valid` is false.
void require_valid(bool valid, const std::string& why);

// The checks: "<name>: <value> must ..." in *why on failure (selfsense/base/check.hpp).
namespace check = base::check;

}  // namespace selfsense::control
