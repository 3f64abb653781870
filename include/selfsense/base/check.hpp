// The one validation vocabulary of the project, with one message format:
//
//   "<name>: <value> <constraint>"   e.g. "Pid.gains.kp: -1 must be >= 0",
//                                         "hysteresis.levels: 4 must be within [8, 1024]"
//
// <name> is what the reader looks for (a parameter, "PrandtlIshlinskii.thresholds[1]", or a
// configuration key path), <value> the shortest text that reads back as the same number
// (format_number). Each check returns true when the value passes; otherwise it writes the
// message to *why (when why is not null) and returns false, so checks chain with &&. The
// operators, the control laws and the plant's configuration all validate with these.
// Allocates on failure only; not for the real-time path (validation happens at construction).
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>

#include "selfsense/base/format_number.hpp"

namespace selfsense::base::check {

// The message for a violated constraint: "<name>: <value> <constraint>".
[[nodiscard]] std::string violation(std::string_view name, std::string_view value,
                                    std::string_view constraint);
template <typename T>
requires std::is_arithmetic_v<T>
[[nodiscard]] std::string violation(std::string_view name, T value, std::string_view constraint) {
  if constexpr (std::is_floating_point_v<T>) {
    return violation(name, format_number(static_cast<double>(value)), constraint);
  } else {
    return violation(name, std::to_string(value), constraint);
  }
}

// Writes "<name>: <message>" and returns false: for constraints without a value of their own
// ("a has 3 elements but b has 2").
bool fail(std::string_view name, std::string_view message, std::string* why);

// Writes violation(name, value, constraint) unless `holds`; returns `holds`.
template <typename T>
requires std::is_arithmetic_v<T>
bool require(bool holds, std::string_view name, T value, std::string_view constraint,
             std::string* why) {
  if (!holds && why != nullptr) *why = violation(name, value, constraint);
  return holds;
}

bool finite(std::string_view name, double value, std::string* why);
bool positive(std::string_view name, double value, std::string* why);
bool non_negative(std::string_view name, double value, std::string* why);
// value < limit; `limit_text` says where the limit comes from ("0.45 * sample rate").
bool below(std::string_view name, double value, double limit, std::string_view limit_text,
           std::string* why);
// Element-wise, naming the element: "<name>[i]".
bool all_finite(std::string_view name, std::span<const double> values, std::string* why);
bool all_non_negative(std::string_view name, std::span<const double> values, std::string* why);
bool all_positive(std::string_view name, std::span<const double> values, std::string* why);
// Strictly increasing and every element > lower_bound (use 0 for positive thresholds).
bool strictly_increasing_above(std::string_view name, std::span<const double> values,
                               double lower_bound, std::string* why);
// Strictly decreasing and every element < upper_bound (use 0 for negative thresholds).
bool strictly_decreasing_below(std::string_view name, std::span<const double> values,
                               double upper_bound, std::string* why);
// "<name_a> has 3 elements but <name_b> has 2".
bool same_size(std::string_view name_a, std::size_t size_a, std::string_view name_b,
               std::size_t size_b, std::string* why);

}  // namespace selfsense::base::check
