#include "selfsense/base/check.hpp"

#include <cmath>
#include <utility>

namespace selfsense::base::check {
namespace {

bool failed(std::string* why, std::string message) {
  if (why != nullptr) *why = std::move(message);
  return false;
}

std::string indexed(std::string_view name, std::size_t index) {
  return std::string(name) + '[' + std::to_string(index) + ']';
}

bool monotone_from(std::string_view name, std::span<const double> values, double bound,
                   bool increasing, std::string* why) {
  const std::string relation = increasing ? "must be > " : "must be < ";
  double previous = bound;
  for (std::size_t i = 0; i < values.size(); ++i) {
    const std::string element = indexed(name, i);
    if (!finite(element, values[i], why)) return false;
    if (!(increasing ? values[i] > previous : values[i] < previous)) {
      const std::string limit =
          i == 0 ? format_number(bound) : indexed(name, i - 1) + " = " + format_number(previous);
      return failed(why, violation(element, values[i], relation + limit));
    }
    previous = values[i];
  }
  return true;
}

}  // namespace

std::string violation(std::string_view name, std::string_view value, std::string_view constraint) {
  std::string text(name);
  text += ": ";
  text += value;
  text += ' ';
  text += constraint;
  return text;
}

bool fail(std::string_view name, std::string_view message, std::string* why) {
  return failed(why, std::string(name) + ": " + std::string(message));
}

bool finite(std::string_view name, double value, std::string* why) {
  return require(std::isfinite(value), name, value, "must be finite", why);
}

bool positive(std::string_view name, double value, std::string* why) {
  return finite(name, value, why) && require(value > 0.0, name, value, "must be > 0", why);
}

bool non_negative(std::string_view name, double value, std::string* why) {
  return finite(name, value, why) && require(value >= 0.0, name, value, "must be >= 0", why);
}

bool below(std::string_view name, double value, double limit, std::string_view limit_text,
           std::string* why) {
  if (!finite(name, value, why)) return false;
  return require(value < limit, name, value,
                 "must be < " + std::string(limit_text) + " = " + format_number(limit), why);
}

bool all_finite(std::string_view name, std::span<const double> values, std::string* why) {
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!finite(indexed(name, i), values[i], why)) return false;
  }
  return true;
}

bool all_non_negative(std::string_view name, std::span<const double> values, std::string* why) {
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!non_negative(indexed(name, i), values[i], why)) return false;
  }
  return true;
}

bool all_positive(std::string_view name, std::span<const double> values, std::string* why) {
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!positive(indexed(name, i), values[i], why)) return false;
  }
  return true;
}

bool strictly_increasing_above(std::string_view name, std::span<const double> values,
                               double lower_bound, std::string* why) {
  return monotone_from(name, values, lower_bound, true, why);
}

bool strictly_decreasing_below(std::string_view name, std::span<const double> values,
                               double upper_bound, std::string* why) {
  return monotone_from(name, values, upper_bound, false, why);
}

bool same_size(std::string_view name_a, std::size_t size_a, std::string_view name_b,
               std::size_t size_b, std::string* why) {
  if (size_a == size_b) return true;
  return failed(why, std::string(name_a) + " has " + std::to_string(size_a) + " elements but " +
                         std::string(name_b) + " has " + std::to_string(size_b));
}

}  // namespace selfsense::base::check
