#include "channel_data.hpp"

#include <cmath>

namespace selfsense::diagnosis::detail {

std::vector<double> response_to_drive(std::span<const double> y, double coupling,
                                      std::span<const double> stress) {
  std::vector<double> r(y.begin(), y.end());
  for (std::size_t k = 0; k < stress.size() && k < r.size(); ++k)
    r[k] -= coupling * stress[k];
  return r;
}

std::vector<bool> hold_finite(std::vector<double>& y) {
  std::vector<bool> usable(y.size());
  double last = 0.0;
  for (const double v : y) {
    if (std::isfinite(v)) {
      last = v;
      break;
    }
  }
  for (std::size_t k = 0; k < y.size(); ++k) {
    usable[k] = std::isfinite(y[k]);
    if (usable[k]) {
      last = y[k];
    } else {
      y[k] = last;
    }
  }
  return usable;
}

double coupling_of(const models::SideModel& side) {
  return side.linear_gains.empty() ? 0.0 : side.linear_gains.front();
}

double coupling_of(const std::optional<models::SideModel>& side) {
  return side ? coupling_of(*side) : 0.0;
}

}  // namespace selfsense::diagnosis::detail
