// Parameter validation shared by every operator.
//
// Operators validate their parameters when they are constructed (never in step()), and reject
// a bad set with a ParameterError whose message names the parameter and the violated
// constraint: "PrandtlIshlinskii.thresholds[3]: -0.1 must be > 0". Each Params struct also has
// a non-throwing `bool is_valid(std::string* why) const` for callers that collect problems
// (configuration loaders).
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>

#include "selfsense/base/check.hpp"
#include "selfsense/base/format_number.hpp"

namespace selfsense::operators {

class ParameterError final : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// Shortest text that reads back as the same double ("0.2", not "0.20000000000000001").
using base::format_number;

// Throws ParameterError(why) when `valid` is false. Keeps constructors to one line.
void require_valid(bool valid, const std::string& why);

// The checks: "<name>: <value> must ..." in *why on failure (selfsense/base/check.hpp).
namespace check = base::check;

}  // namespace selfsense::operators
