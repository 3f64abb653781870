// Parameter validation shared by every operator.
//
// Operators validate their parameters when they are constructed (never in step()), and reject
// a bad set with a ParameterError whose message names the parameter and the violated
// constraint: "PrandtlIshlinskii.thresholds[3]: -0.1 must be > 0". Each Params struct also has
// a non-throwing `bool is_valid(std::string* why) const` for callers that collect problems
// (configuration loaders).
#pragma once

#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

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

namespace check {

// Each returns false and writes "<name>: <value> must ..." to *why (if non-null) on failure.
bool finite(std::string_view name, double value, std::string* why);
bool positive(std::string_view name, double value, std::string* why);
bool non_negative(std::string_view name, double value, std::string* why);
bool all_finite(std::string_view name, std::span<const double> values, std::string* why);
bool all_non_negative(std::string_view name, std::span<const double> values, std::string* why);
bool all_positive(std::string_view name, std::span<const double> values, std::string* why);
// Strictly increasing and every element > lower_bound (use 0 for positive thresholds).
bool strictly_increasing_above(std::string_view name, std::span<const double> values,
                               double lower_bound, std::string* why);
// Strictly decreasing and every element < upper_bound (use 0 for negative thresholds).
bool strictly_decreasing_below(std::string_view name, std::span<const double> values,
                               double upper_bound, std::string* why);
bool same_size(std::string_view name_a, std::size_t size_a, std::string_view name_b,
               std::size_t size_b, std::string* why);

}  // namespace check
}  // namespace selfsense::operators
