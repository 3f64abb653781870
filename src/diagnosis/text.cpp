#include "text.hpp"

#include <algorithm>
#include <iomanip>
#include <sstream>

namespace selfsense::diagnosis::detail {

double range_of(std::span<const double> x) {
  if (x.empty()) return 0.0;
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  return *hi - *lo;
}

std::string format(const char* fmt, double a, double b, double c) {
  const double args[3] = {a, b, c};
  std::size_t next = 0;
  std::ostringstream out;
  for (const char* p = fmt; *p != '\0'; ++p) {
    if (*p != '%') {
      out << *p;
      continue;
    }
    ++p;
    if (*p == '%') {
      out << '%';
      continue;
    }
    const bool sign = *p == '+';
    if (sign) ++p;
    int digits = 6;
    if (*p == '.') {
      digits = 0;
      for (++p; *p >= '0' && *p <= '9'; ++p)
        digits = digits * 10 + (*p - '0');
    }
    const double v = next < 3 ? args[next++] : 0.0;
    if (sign && !(v < 0.0)) out << '+';
    if (*p == 'f') {
      out << std::fixed << std::setprecision(digits) << v << std::defaultfloat;
    } else {
      out << std::setprecision(std::max(digits, 1)) << v;
    }
  }
  return out.str();
}

}  // namespace selfsense::diagnosis::detail
