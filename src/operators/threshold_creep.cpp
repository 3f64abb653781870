#include "selfsense/operators/threshold_creep.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <utility>

#include "selfsense/operators/kernels.hpp"
#include "selfsense/operators/parameter_error.hpp"

namespace selfsense::operators {

bool ThresholdCreep::Params::is_valid(std::string* why) const {
  // Thresholds are >= 0 (the first may be 0); once non-negativity holds, the bound -1 of the
  // ordering check can never be the binding one.
  if (!check::all_non_negative("ThresholdCreep.thresholds", thresholds, why) ||
      !check::strictly_increasing_above("ThresholdCreep.thresholds", thresholds, -1.0, why) ||
      !check::all_non_negative("ThresholdCreep.weights", weights, why) ||
      !check::all_positive("ThresholdCreep.eigenvalues", eigenvalues, why)) {
    return false;
  }
  return check::same_size("ThresholdCreep.weights", weights.size(),
                          "ThresholdCreep.thresholds x eigenvalues",
                          thresholds.size() * eigenvalues.size(), why);
}

ThresholdCreep::ThresholdCreep(Params params, double sample_time)
    : params_(std::move(params)), sample_time_(sample_time) {
  std::string why;
  require_valid(
      params_.is_valid(&why) && check::positive("ThresholdCreep.sample_time", sample_time, &why),
      why);
  const std::size_t rows = params_.thresholds.size();
  const std::size_t cols = params_.eigenvalues.size();
  gains_.resize(rows * cols);
  for (std::size_t i = 0; i < rows; ++i) {
    for (std::size_t j = 0; j < cols; ++j) {
      gains_[i * cols + j] = -std::expm1(-params_.eigenvalues[j] * sample_time_);
    }
  }
  state_.assign(rows + rows * cols, 0.0);
}

double ThresholdCreep::step(double x) noexcept {
  const std::span<double> p = plays();
  const std::span<double> z = lags();
  kernels::play_bank_step(x, params_.thresholds, p);
  const std::size_t cols = params_.eigenvalues.size();
  double sum = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const std::size_t row = i * cols;
    sum +=
        kernels::lag_bank_step(p[i], std::span(gains_).subspan(row, cols),
                               std::span(params_.weights).subspan(row, cols), z.subspan(row, cols));
  }
  return sum;
}

void ThresholdCreep::apply(std::span<const double> x, std::span<double> y) noexcept {
  assert(x.size() == y.size());
  for (std::size_t k = 0; k < x.size(); ++k)
    y[k] = step(x[k]);
}

double ThresholdCreep::output() const noexcept {
  return kernels::dot(params_.weights, std::span(state_).subspan(params_.thresholds.size()));
}

void ThresholdCreep::set_state(std::span<const double> state) noexcept {
  assert(state.size() == state_.size());
  std::copy(state.begin(), state.end(), state_.begin());
}

void ThresholdCreep::reset(double x) noexcept {
  std::fill(state_.begin(), state_.end(), x);
}

void NonlinearCreep::apply(std::span<const double> x, std::span<double> y) noexcept {
  assert(x.size() == y.size());
  for (std::size_t k = 0; k < x.size(); ++k)
    y[k] = step(x[k]);
}

ThresholdCreep::Params rank_one_creep(const PrandtlIshlinskii::Params& hysteresis,
                                      const LinearCreep::Params& creep) {
  std::string why;
  require_valid(hysteresis.is_valid(&why) && creep.is_valid(&why), "rank_one_creep: " + why);
  ThresholdCreep::Params out;
  out.thresholds.push_back(0.0);
  out.thresholds.insert(out.thresholds.end(), hysteresis.thresholds.begin(),
                        hysteresis.thresholds.end());
  out.eigenvalues = creep.eigenvalues;
  std::vector<double> w{hysteresis.linear_weight};
  w.insert(w.end(), hysteresis.weights.begin(), hysteresis.weights.end());
  for (std::size_t i = 0; i < w.size(); ++i) {
    require_valid(w[i] >= 0.0, "rank_one_creep: hysteresis weight " + std::to_string(i) +
                                   " is negative; L[H[x]] then needs negative creep weights");
    for (const double cj : creep.weights)
      out.weights.push_back(w[i] * cj);
  }
  return out;
}

ThresholdCreep::Params NonlinearCreep::as_threshold_creep() const {
  return rank_one_creep(hysteresis_.params(), creep_.params());
}

}  // namespace selfsense::operators
