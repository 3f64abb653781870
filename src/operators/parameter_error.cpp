#include "selfsense/operators/parameter_error.hpp"

#include <cmath>
#include <cstddef>
#include <sstream>

namespace selfsense::operators {

void require_valid(bool valid, const std::string& why) {
  if (!valid) throw ParameterError(why);
}

namespace check {
namespace {

bool fail(std::string* why, const std::string& message) {
  if (why != nullptr) *why = message;
  return false;
}

std::string describe(std::string_view name, double value, std::string_view constraint) {
  return std::string(name) + ": " + format_number(value) + ' ' + std::string(constraint);
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
      return fail(why, describe(element, values[i], relation + limit));
    }
    previous = values[i];
  }
  return true;
}

}  // namespace

bool finite(std::string_view name, double value, std::string* why) {
  return std::isfinite(value) || fail(why, describe(name, value, "must be finite"));
}

bool positive(std::string_view name, double value, std::string* why) {
  return finite(name, value, why) &&
         (value > 0.0 || fail(why, describe(name, value, "must be > 0")));
}

bool non_negative(std::string_view name, double value, std::string* why) {
  return finite(name, value, why) &&
         (value >= 0.0 || fail(why, describe(name, value, "must be >= 0")));
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
  std::ostringstream out;
  out << name_a << " has " << size_a << " elements but " << name_b << " has " << size_b;
  return fail(why, out.str());
}

}  // namespace check
}  // namespace selfsense::operators
