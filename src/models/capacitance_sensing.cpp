#include "selfsense/models/capacitance_sensing.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "selfsense/operators/parameter_error.hpp"

namespace selfsense::models {

bool CapacitanceEstimator::Params::is_valid(std::string* why) const {
  namespace check = operators::check;
  if (!check::positive("CapacitanceEstimator.forgetting", forgetting, why) ||
      !check::finite("CapacitanceEstimator.initial_estimate", initial_estimate, why) ||
      !check::positive("CapacitanceEstimator.initial_variance", initial_variance, why) ||
      !check::non_negative("CapacitanceEstimator.min_step", min_step, why)) {
    return false;
  }
  if (forgetting > 1.0) {
    if (why != nullptr) {
      *why = "CapacitanceEstimator.forgetting: " + operators::format_number(forgetting) +
             " must be <= 1";
    }
    return false;
  }
  return true;
}

CapacitanceEstimator::CapacitanceEstimator(const Params& params)
    : params_(params), c_(params.initial_estimate), p_(params.initial_variance) {
  std::string why;
  operators::require_valid(params.is_valid(&why), why);
}

double CapacitanceEstimator::step(double e, double d) noexcept {
  if (!std::isfinite(e) || !std::isfinite(d)) return c_;  // a bad sample teaches nothing
  if (primed_) {
    const double de = e - e_prev_;
    const double dd = d - d_prev_;
    if (std::abs(de) > params_.min_step) {
      const double gain = p_ * de / (params_.forgetting + de * p_ * de);
      c_ += gain * (dd - c_ * de);
      p_ = (p_ - gain * de * p_) / params_.forgetting;
    }
  }
  e_prev_ = e;
  d_prev_ = d;
  primed_ = true;
  return c_;
}

CapacitanceCharacteristic fit_capacitance_characteristic(std::span<const double> capacitance,
                                                         std::span<const double> stress,
                                                         bool quadratic) {
  const std::size_t n = capacitance.size();
  if (n < 3 || stress.size() != n) {
    throw std::invalid_argument(
        "fit_capacitance_characteristic: capacitance and stress need the same length >= 3");
  }
  CapacitanceCharacteristic out;
  out.reference =
      std::accumulate(capacitance.begin(), capacitance.end(), 0.0) / static_cast<double>(n);
  const auto [lo, hi] = std::minmax_element(capacitance.begin(), capacitance.end());
  const double span = *hi - *lo;
  if (!(span > 0.0)) throw std::invalid_argument("fit_capacitance_characteristic: constant input");
  const Eigen::Index cols = quadratic ? 3 : 2;
  Eigen::MatrixXd a(static_cast<Eigen::Index>(n), cols);
  Eigen::VectorXd y(static_cast<Eigen::Index>(n));
  for (std::size_t k = 0; k < n; ++k) {
    const auto r = static_cast<Eigen::Index>(k);
    const double x = (capacitance[k] - out.reference) / span;  // scaled for conditioning
    a(r, 0) = 1.0;
    a(r, 1) = x;
    if (quadratic) a(r, 2) = x * x;
    y(r) = stress[k];
  }
  const Eigen::VectorXd b = a.colPivHouseholderQr().solve(y);
  out.b0 = b(0);
  out.b1 = b(1) / span;
  out.b2 = quadratic ? b(2) / (span * span) : 0.0;
  return out;
}

}  // namespace selfsense::models
