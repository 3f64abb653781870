#include "selfsense/operators/modified_prandtl_ishlinskii.hpp"

#include <cassert>
#include <cstddef>

namespace selfsense::operators {

void ModifiedPrandtlIshlinskii::apply(std::span<const double> x, std::span<double> y) noexcept {
  assert(x.size() == y.size());
  for (std::size_t k = 0; k < x.size(); ++k)
    y[k] = step(x[k]);
}

ModifiedPrandtlIshlinskiiInverse ModifiedPrandtlIshlinskii::inverse() const {
  return {hysteresis_.inverse(), superposition_.inverse()};
}

void ModifiedPrandtlIshlinskiiInverse::apply(std::span<const double> y,
                                             std::span<double> x) noexcept {
  assert(x.size() == y.size());
  for (std::size_t k = 0; k < y.size(); ++k)
    x[k] = step(y[k]);
}

}  // namespace selfsense::operators
