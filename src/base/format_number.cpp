#include "selfsense/base/format_number.hpp"

#include <array>
#include <charconv>

namespace selfsense::base {

std::string format_number(double value) {
  // The longest shortest-form double ("-2.2250738585072014e-308") is 24 characters.
  std::array<char, 32> buffer{};
  const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  return {buffer.data(), result.ptr};
}

}  // namespace selfsense::base
