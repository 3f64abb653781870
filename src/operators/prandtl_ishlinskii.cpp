#include "selfsense/operators/prandtl_ishlinskii.hpp"

#include <algorithm>
#include <cassert>
#include <string>

#include "selfsense/operators/kernels.hpp"
#include "selfsense/operators/parameter_error.hpp"

namespace selfsense::operators {

bool PrandtlIshlinskii::Params::is_valid(std::string* why) const {
  if (!check::positive("PrandtlIshlinskii.linear_weight", linear_weight, why) ||
      !check::strictly_increasing_above("PrandtlIshlinskii.thresholds", thresholds, 0.0, why) ||
      !check::all_finite("PrandtlIshlinskii.weights", weights, why) ||
      !check::same_size("PrandtlIshlinskii.thresholds", thresholds.size(),
                        "PrandtlIshlinskii.weights", weights.size(), why)) {
    return false;
  }
  double partial_sum = linear_weight;
  for (std::size_t i = 0; i < weights.size(); ++i) {
    partial_sum += weights[i];
    if (!(partial_sum > 0.0)) {
      if (why != nullptr) {
        *why = "PrandtlIshlinskii.weights[" + std::to_string(i) +
               "]: partial sum linear_weight + weights[0.." + std::to_string(i) +
               "] = " + format_number(partial_sum) +
               " must be > 0 (else the operator is not invertible)";
      }
      return false;
    }
  }
  return true;
}

PrandtlIshlinskii::PrandtlIshlinskii(const Params& params) {
  std::string why;
  require_valid(params.is_valid(&why), why);
  thresholds_.reserve(params.thresholds.size() + 1);
  thresholds_.push_back(0.0);
  thresholds_.insert(thresholds_.end(), params.thresholds.begin(), params.thresholds.end());
  weights_.reserve(params.weights.size() + 1);
  weights_.push_back(params.linear_weight);
  weights_.insert(weights_.end(), params.weights.begin(), params.weights.end());
  plays_.assign(thresholds_.size(), 0.0);
}

PrandtlIshlinskii::Params PrandtlIshlinskii::params() const {
  return Params{weights_.front(),
                {thresholds_.begin() + 1, thresholds_.end()},
                {weights_.begin() + 1, weights_.end()}};
}

double PrandtlIshlinskii::step(double x) noexcept {
  kernels::play_bank_step(x, thresholds_, plays_);
  return kernels::dot(weights_, plays_);
}

void PrandtlIshlinskii::apply(std::span<const double> x, std::span<double> y) noexcept {
  assert(x.size() == y.size());
  for (std::size_t k = 0; k < x.size(); ++k)
    y[k] = step(x[k]);
}

double PrandtlIshlinskii::output() const noexcept {
  return kernels::dot(weights_, plays_);
}

void PrandtlIshlinskii::set_state(std::span<const double> plays) noexcept {
  assert(plays.size() == plays_.size());
  std::copy(plays.begin(), plays.end(), plays_.begin());
}

void PrandtlIshlinskii::reset(double x) noexcept {
  std::fill(plays_.begin(), plays_.end(), x);
}

PrandtlIshlinskii PrandtlIshlinskii::inverse() const {
  PrandtlIshlinskii inv;
  const std::size_t n = thresholds_.size();
  inv.thresholds_.resize(n);
  inv.weights_.resize(n);
  inv.plays_.resize(n);
  inverse_parameters(thresholds_, weights_, inv.thresholds_, inv.weights_);
  inverse_state(weights_, plays_, inv.plays_);
  return inv;
}

void PrandtlIshlinskii::inverse_parameters(std::span<const double> r, std::span<const double> w,
                                           std::span<double> r_inv,
                                           std::span<double> w_inv) noexcept {
  assert(r.size() == w.size() && r_inv.size() == r.size() && w_inv.size() == w.size());
  // r'_i = sum_{j<=i} w_j (r_i - r_j) = W_i r_i - sum_{j<=i} w_j r_j.
  double partial_weight = 0.0;
  double partial_moment = 0.0;
  double previous_partial = 0.0;
  for (std::size_t i = 0; i < r.size(); ++i) {
    partial_weight += w[i];
    partial_moment += w[i] * r[i];
    r_inv[i] = partial_weight * r[i] - partial_moment;
    w_inv[i] = i == 0 ? 1.0 / w[0] : -w[i] / (partial_weight * previous_partial);
    previous_partial = partial_weight;
  }
}

void PrandtlIshlinskii::inverse_state(std::span<const double> w, std::span<const double> plays,
                                      std::span<double> inverse_plays) noexcept {
  assert(w.size() == plays.size() && inverse_plays.size() == plays.size());
  // Backward pass for the suffix sums, forward pass for the partial weights W_i.
  double suffix = 0.0;
  for (std::size_t i = plays.size(); i-- > 0;) {
    inverse_plays[i] = suffix;
    suffix += w[i] * plays[i];
  }
  double partial_weight = 0.0;
  for (std::size_t i = 0; i < plays.size(); ++i) {
    partial_weight += w[i];
    inverse_plays[i] += partial_weight * plays[i];
  }
}

}  // namespace selfsense::operators
