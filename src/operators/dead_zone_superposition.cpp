#include "selfsense/operators/dead_zone_superposition.hpp"

#include <cassert>
#include <cstddef>
#include <string>
#include <utility>

#include "selfsense/operators/kernels.hpp"
#include "selfsense/operators/parameter_error.hpp"

namespace selfsense::operators {
namespace {

// Slopes on every interval of one side stay positive.
bool slopes_positive(const char* side, double linear_weight, std::span<const double> weights,
                     std::string* why) {
  double slope = linear_weight;
  for (std::size_t i = 0; i < weights.size(); ++i) {
    slope += weights[i];
    if (!(slope > 0.0)) {
      if (why != nullptr) {
        *why = std::string("DeadZoneSuperposition.") + side + "_weights[" + std::to_string(i) +
               "]: slope linear_weight + " + side + "_weights[0.." + std::to_string(i) +
               "] = " + format_number(slope) +
               " must be > 0 (else the characteristic is not invertible)";
      }
      return false;
    }
  }
  return true;
}

// Inverse thresholds and weights of one side (see header).
void invert_side(const DeadZoneSuperposition& s, std::span<const double> thresholds,
                 std::span<const double> weights, std::vector<double>& inv_thresholds,
                 std::vector<double>& inv_weights) {
  inv_thresholds.resize(thresholds.size());
  inv_weights.resize(weights.size());
  double slope = s.params().linear_weight;
  for (std::size_t i = 0; i < thresholds.size(); ++i) {
    inv_thresholds[i] = s.evaluate(thresholds[i]);
    const double next = slope + weights[i];
    inv_weights[i] = 1.0 / next - 1.0 / slope;
    slope = next;
  }
}

}  // namespace

bool DeadZoneSuperposition::Params::is_valid(std::string* why) const {
  return check::positive("DeadZoneSuperposition.linear_weight", linear_weight, why) &&
         check::strictly_increasing_above("DeadZoneSuperposition.upper_thresholds",
                                          upper_thresholds, 0.0, why) &&
         check::strictly_decreasing_below("DeadZoneSuperposition.lower_thresholds",
                                          lower_thresholds, 0.0, why) &&
         check::all_finite("DeadZoneSuperposition.upper_weights", upper_weights, why) &&
         check::all_finite("DeadZoneSuperposition.lower_weights", lower_weights, why) &&
         check::same_size("DeadZoneSuperposition.upper_thresholds", upper_thresholds.size(),
                          "DeadZoneSuperposition.upper_weights", upper_weights.size(), why) &&
         check::same_size("DeadZoneSuperposition.lower_thresholds", lower_thresholds.size(),
                          "DeadZoneSuperposition.lower_weights", lower_weights.size(), why) &&
         slopes_positive("upper", linear_weight, upper_weights, why) &&
         slopes_positive("lower", linear_weight, lower_weights, why);
}

DeadZoneSuperposition::DeadZoneSuperposition(Params params) : params_(std::move(params)) {
  std::string why;
  require_valid(params_.is_valid(&why), why);
}

double DeadZoneSuperposition::evaluate(double y) const noexcept {
  return params_.linear_weight * y +
         kernels::upper_dead_zone_sum(y, params_.upper_thresholds, params_.upper_weights) +
         kernels::lower_dead_zone_sum(y, params_.lower_thresholds, params_.lower_weights);
}

void DeadZoneSuperposition::apply(std::span<const double> y, std::span<double> out) const noexcept {
  assert(y.size() == out.size());
  for (std::size_t k = 0; k < y.size(); ++k)
    out[k] = evaluate(y[k]);
}

double DeadZoneSuperposition::slope(double y) const noexcept {
  double g = params_.linear_weight;
  for (std::size_t i = 0; i < params_.upper_thresholds.size(); ++i) {
    if (y >= params_.upper_thresholds[i]) g += params_.upper_weights[i];
  }
  for (std::size_t i = 0; i < params_.lower_thresholds.size(); ++i) {
    if (y < params_.lower_thresholds[i]) g += params_.lower_weights[i];
  }
  return g;
}

DeadZoneSuperposition DeadZoneSuperposition::inverse() const {
  Params inv;
  inv.linear_weight = 1.0 / params_.linear_weight;
  invert_side(*this, params_.upper_thresholds, params_.upper_weights, inv.upper_thresholds,
              inv.upper_weights);
  invert_side(*this, params_.lower_thresholds, params_.lower_weights, inv.lower_thresholds,
              inv.lower_weights);
  return DeadZoneSuperposition(std::move(inv));
}

}  // namespace selfsense::operators
