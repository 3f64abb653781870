#include "selfsense/operators/play.hpp"

#include <cassert>
#include <cstddef>

#include "selfsense/operators/parameter_error.hpp"

namespace selfsense::operators {

PlayOperator::PlayOperator(double threshold, double initial_output)
    : threshold_(threshold), output_(initial_output) {
  std::string why;
  require_valid(check::non_negative("PlayOperator.threshold", threshold, &why), why);
}

void PlayOperator::apply(std::span<const double> x, std::span<double> y) noexcept {
  assert(x.size() == y.size());
  for (std::size_t k = 0; k < x.size(); ++k)
    y[k] = step(x[k]);
}

StopOperator::StopOperator(double threshold, double last_input, double last_output)
    : play_(threshold, last_input - last_output), last_input_(last_input) {}

void StopOperator::apply(std::span<const double> x, std::span<double> y) noexcept {
  assert(x.size() == y.size());
  for (std::size_t k = 0; k < x.size(); ++k)
    y[k] = step(x[k]);
}

}  // namespace selfsense::operators
