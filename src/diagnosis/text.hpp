// Small helpers of the diagnosis's wording (the math libraries do no stdio).
#pragma once

#include <span>
#include <string>

namespace selfsense::diagnosis::detail {

// max - min of a signal (0 when empty).
[[nodiscard]] double range_of(std::span<const double> x);

// printf-style "%.3g", "%+.3g", "%.0f" and "%%" only, up to three numbers.
[[nodiscard]] std::string format(const char* fmt, double a, double b = 0.0, double c = 0.0);

}  // namespace selfsense::diagnosis::detail
