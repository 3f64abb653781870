#include "selfsense/operators/hysteresis_creep.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <utility>

#include "selfsense/operators/kernels.hpp"
#include "selfsense/operators/parameter_error.hpp"

namespace selfsense::operators {
namespace {

// Position of value in the sorted union (it is there by construction).
std::size_t index_in(std::span<const double> sorted, double value) {
  return static_cast<std::size_t>(std::lower_bound(sorted.begin(), sorted.end(), value) -
                                  sorted.begin());
}

}  // namespace

bool HysteresisCreep::Params::is_valid(std::string* why) const {
  const auto prefixed = [why](const char* prefix, bool ok) {
    if (!ok && why != nullptr) *why = std::string("HysteresisCreep.") + prefix + "." + *why;
    return ok;
  };
  return prefixed("hysteresis", hysteresis.is_valid(why)) &&
         prefixed("superposition", superposition.is_valid(why)) &&
         prefixed("creep", creep.is_valid(why)) && prefixed("hinges", hinges.is_valid(why));
}

HysteresisCreep::Params HysteresisCreep::with_nonlinear_creep(
    const PrandtlIshlinskii::Params& hysteresis, const DeadZoneSuperposition::Params& shape,
    const LinearCreep::Params& creep) {
  return Params{hysteresis, shape, rank_one_creep(hysteresis, creep)};
}

HysteresisCreep::HysteresisCreep(Params params, double sample_time)
    : params_(std::move(params)), sample_time_(sample_time) {
  std::string why;
  require_valid(
      params_.is_valid(&why) && check::positive("HysteresisCreep.sample_time", sample_time, &why),
      why);
  shape_ = DeadZoneSuperposition(params_.superposition);
  shape_inverse_ = shape_.inverse();

  // Shared play bank: r_0 = 0, then the union of both threshold sets.
  const auto& h = params_.hysteresis;
  const auto& c = params_.creep;
  thresholds_.push_back(0.0);
  std::set_union(h.thresholds.begin(), h.thresholds.end(), c.thresholds.begin(), c.thresholds.end(),
                 std::back_inserter(thresholds_));
  thresholds_.insert(thresholds_.end(), params_.hinges.thresholds.begin(),
                     params_.hinges.thresholds.end());
  std::sort(thresholds_.begin(), thresholds_.end());
  thresholds_.erase(std::unique(thresholds_.begin(), thresholds_.end()), thresholds_.end());
  for (const double r : params_.hinges.thresholds)
    hinge_rows_.push_back(index_in(thresholds_, r));
  scale_ = std::max(thresholds_.back(), 1e-300);
  const std::size_t n = thresholds_.size();
  hysteresis_weights_.assign(n, 0.0);
  hysteresis_weights_[0] = h.linear_weight;
  for (std::size_t i = 0; i < h.thresholds.size(); ++i) {
    hysteresis_weights_[index_in(thresholds_, h.thresholds[i])] = h.weights[i];
  }

  const std::size_t cols = c.eigenvalues.size();
  creep_weights_ = c.weights;
  creep_gains_.resize(creep_weights_.size());
  carry_weights_.resize(creep_weights_.size());
  effective_weights_ = hysteresis_weights_;
  for (std::size_t i = 0; i < c.thresholds.size(); ++i) {
    const std::size_t row = index_in(thresholds_, c.thresholds[i]);
    creep_rows_.push_back(row);
    for (std::size_t j = 0; j < cols; ++j) {
      const std::size_t e = i * cols + j;
      creep_gains_[e] = -std::expm1(-c.eigenvalues[j] * sample_time_);
      carry_weights_[e] = creep_weights_[e] * (1.0 - creep_gains_[e]);
      effective_weights_[row] += creep_weights_[e] * creep_gains_[e];
    }
  }
  inverse_thresholds_.resize(n);
  inverse_weights_.resize(n);
  PrandtlIshlinskii::inverse_parameters(thresholds_, effective_weights_, inverse_thresholds_,
                                        inverse_weights_);
  scratch_.resize(n);
  state_.assign(n + creep_weights_.size(), 0.0);
}

double HysteresisCreep::hinge_sum(std::span<const double> plays) const noexcept {
  double sum = 0.0;
  const PlayHinges& g = params_.hinges;
  for (std::size_t h = 0; h < hinge_rows_.size(); ++h)
    sum += g.weights[h] * std::max(plays[hinge_rows_[h]] - g.levels[h], 0.0);
  return sum;
}

double HysteresisCreep::inner_step(double x) noexcept {
  const std::span<double> p = plays();
  const std::span<double> z = lags();
  kernels::play_bank_step(x, thresholds_, p);
  double sum = kernels::dot(hysteresis_weights_, p) + hinge_sum(p);
  const std::size_t cols = params_.creep.eigenvalues.size();
  for (std::size_t i = 0; i < creep_rows_.size(); ++i) {
    const std::size_t e = i * cols;
    sum += kernels::lag_bank_step(p[creep_rows_[i]], std::span(creep_gains_).subspan(e, cols),
                                  std::span(creep_weights_).subspan(e, cols), z.subspan(e, cols));
  }
  return sum;
}

double HysteresisCreep::step(double x) noexcept {
  return shape_.evaluate(inner_step(x));
}

void HysteresisCreep::apply(std::span<const double> x, std::span<double> y) noexcept {
  assert(x.size() == y.size());
  for (std::size_t k = 0; k < x.size(); ++k)
    y[k] = step(x[k]);
}

double HysteresisCreep::input_for(double y) noexcept {
  const double carry = kernels::dot(carry_weights_, lags());
  const double target = shape_inverse_.evaluate(y) - carry;
  if (!hinge_rows_.empty()) return solve_inner(target);
  PrandtlIshlinskii::inverse_state(effective_weights_, plays(), scratch_);
  kernels::play_bank_step(target, inverse_thresholds_, scratch_);
  return kernels::dot(inverse_weights_, scratch_);
}

// sum_i (w_i + b_i) p_i(x) + hinges(p(x)) with p_i(x) = clamp(p_i, x - r_i, x + r_i): the
// creep-free part of this sample's H + K (the carry is the rest). A play moves with x (slope
// 1) where the clamp binds, else it holds.
double HysteresisCreep::trial_inner(double x, double* slope) const noexcept {
  const std::span<const double> p = std::span<const double>(state_).first(play_count());
  const auto moved = [&](std::size_t i) {
    return std::min(std::max(p[i], x - thresholds_[i]), x + thresholds_[i]);
  };
  const auto moving = [&](std::size_t i, double now) {
    return now != p[i] || thresholds_[i] == 0.0;
  };
  double value = 0.0;
  double rate = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double now = moved(i);
    value += effective_weights_[i] * now;
    if (moving(i, now)) rate += effective_weights_[i];
  }
  const PlayHinges& g = params_.hinges;
  for (std::size_t h = 0; h < hinge_rows_.size(); ++h) {
    const std::size_t i = hinge_rows_[h];
    const double now = moved(i);
    if (now > g.levels[h]) {
      value += g.weights[h] * (now - g.levels[h]);
      if (moving(i, now)) rate += g.weights[h];
    }
  }
  *slope = rate;
  return value;
}

double HysteresisCreep::solve_inner(double target) const noexcept {
  if (!std::isfinite(target)) return target;
  // Start where the input is now: the answer is near it for any sample-to-sample change.
  double x = state_[0];
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  double step = scale_;
  constexpr int kIterations = 100;
  for (int it = 0; it < kIterations; ++it) {
    double slope = 0.0;
    const double miss = trial_inner(x, &slope) - target;
    if (miss == 0.0) return x;
    if (miss < 0.0) {
      lo = x;
    } else {
      hi = x;
    }
    const bool bracketed = std::isfinite(lo) && std::isfinite(hi);
    if (bracketed && hi - lo <= 1e-12 * std::max(std::abs(lo), std::abs(hi))) break;
    double next = slope > 0.0 ? x - miss / slope : std::numeric_limits<double>::quiet_NaN();
    // On the root's linear piece Newton lands on the root; what is left is rounding.
    if (std::abs(next - x) <= 1e-12 * std::max(std::abs(x), scale_)) return next;
    if (!(next > lo && next < hi)) {
      if (bracketed) {
        next = 0.5 * (lo + hi);
      } else {  // no bracket yet: walk outwards, doubling
        next = miss < 0.0 ? x + step : x - step;
        step *= 2.0;
      }
    }
    x = next;
  }
  return std::isfinite(lo) && std::isfinite(hi) ? 0.5 * (lo + hi) : x;
}

double HysteresisCreep::inverse_step(double y) noexcept {
  const double x = input_for(y);
  static_cast<void>(inner_step(x));
  return x;
}

void HysteresisCreep::apply_inverse(std::span<const double> y, std::span<double> x) noexcept {
  assert(x.size() == y.size());
  for (std::size_t k = 0; k < y.size(); ++k)
    x[k] = inverse_step(y[k]);
}

double HysteresisCreep::output() const noexcept {
  const std::span<const double> all(state_);
  return shape_.evaluate(kernels::dot(hysteresis_weights_, all.first(play_count())) +
                         hinge_sum(all.first(play_count())) +
                         kernels::dot(creep_weights_, all.subspan(play_count())));
}

void HysteresisCreep::set_state(std::span<const double> state) noexcept {
  assert(state.size() == state_.size());
  std::copy(state.begin(), state.end(), state_.begin());
}

void HysteresisCreep::reset(double x) noexcept {
  std::fill(state_.begin(), state_.end(), x);
}

void HysteresisCreep::set_history(std::span<const double> turning_points) noexcept {
  reset(turning_points.empty() ? 0.0 : turning_points.front());
  for (const double x : turning_points)
    kernels::play_bank_step(x, thresholds_, plays());
  const std::span<double> p = plays();
  const std::span<double> z = lags();
  const std::size_t cols = params_.creep.eigenvalues.size();
  for (std::size_t i = 0; i < creep_rows_.size(); ++i) {
    std::fill_n(z.begin() + static_cast<std::ptrdiff_t>(i * cols), cols, p[creep_rows_[i]]);
  }
}

HysteresisCreepCompensator::HysteresisCreepCompensator(HysteresisCreep model, double input_min,
                                                       double input_max)
    : model_(std::move(model)), input_min_(input_min), input_max_(input_max) {
  std::string why;
  require_valid(check::finite("HysteresisCreepCompensator.input_min", input_min, &why) &&
                    check::finite("HysteresisCreepCompensator.input_max", input_max, &why),
                why);
  require_valid(input_min < input_max, "HysteresisCreepCompensator.input_max: must be > input_min");
}

double HysteresisCreepCompensator::step(double desired_output) noexcept {
  double x = model_.input_for(desired_output);
  if (!(x >= input_min_ && x <= input_max_)) {
    ++saturations_;
    x = std::isnan(x) ? input_min_ : std::clamp(x, input_min_, input_max_);
  }
  static_cast<void>(model_.step(x));
  return x;
}

void HysteresisCreepCompensator::apply(std::span<const double> desired,
                                       std::span<double> input) noexcept {
  assert(desired.size() == input.size());
  for (std::size_t k = 0; k < desired.size(); ++k)
    input[k] = step(desired[k]);
}

}  // namespace selfsense::operators
