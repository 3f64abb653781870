#include "selfsense/operators/linear_creep.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <utility>

#include "selfsense/operators/kernels.hpp"
#include "selfsense/operators/parameter_error.hpp"

namespace selfsense::operators {

bool LinearCreep::Params::is_valid(std::string* why) const {
  if (!check::same_size("LinearCreep.eigenvalues", eigenvalues.size(), "LinearCreep.weights",
                        weights.size(), why) ||
      !check::all_non_negative("LinearCreep.weights", weights, why)) {
    return false;
  }
  return check::all_positive("LinearCreep.eigenvalues", eigenvalues, why);
}

LinearCreep::LinearCreep(Params params, double sample_time)
    : params_(std::move(params)), sample_time_(sample_time) {
  std::string why;
  require_valid(
      params_.is_valid(&why) && check::positive("LinearCreep.sample_time", sample_time, &why), why);
  gains_.resize(params_.eigenvalues.size());
  for (std::size_t j = 0; j < gains_.size(); ++j) {
    gains_[j] = -std::expm1(-params_.eigenvalues[j] * sample_time_);
  }
  states_.assign(gains_.size(), 0.0);
}

double LinearCreep::static_gain() const noexcept {
  double sum = 0.0;
  for (const double c : params_.weights)
    sum += c;
  return sum;
}

double LinearCreep::instant_gain() const noexcept {
  return kernels::dot(params_.weights, gains_);
}

double LinearCreep::step(double x) noexcept {
  return kernels::lag_bank_step(x, gains_, params_.weights, states_);
}

void LinearCreep::apply(std::span<const double> x, std::span<double> y) noexcept {
  assert(x.size() == y.size());
  for (std::size_t k = 0; k < x.size(); ++k)
    y[k] = step(x[k]);
}

double LinearCreep::output() const noexcept {
  return kernels::dot(params_.weights, states_);
}

void LinearCreep::set_state(std::span<const double> states) noexcept {
  assert(states.size() == states_.size());
  std::copy(states.begin(), states.end(), states_.begin());
}

void LinearCreep::reset(double x) noexcept {
  std::fill(states_.begin(), states_.end(), x);
}

double LinearCreep::step_response(const Params& params, double t) noexcept {
  double sum = 0.0;
  for (std::size_t j = 0; j < params.eigenvalues.size(); ++j) {
    sum += params.weights[j] * -std::expm1(-params.eigenvalues[j] * t);
  }
  return sum;
}

std::vector<double> log_spaced_eigenvalues(double fastest, double slowest, std::size_t n) {
  std::string why;
  require_valid(check::positive("log_spaced_eigenvalues.slowest", slowest, &why) &&
                    check::positive("log_spaced_eigenvalues.fastest", fastest, &why),
                why);
  require_valid(n >= 1, "log_spaced_eigenvalues.n: must be >= 1");
  if (n == 1) return {fastest};
  require_valid(fastest > slowest, "log_spaced_eigenvalues: fastest must be > slowest");
  std::vector<double> out(n);
  const double ratio = std::log(slowest / fastest) / static_cast<double>(n - 1);
  for (std::size_t j = 0; j < n; ++j)
    out[j] = fastest * std::exp(ratio * static_cast<double>(j));
  out.back() = slowest;
  return out;
}

}  // namespace selfsense::operators
