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
  if (!hinge_rows_.empty()) {
    last_root_ = solve_inner(target, std::isfinite(last_root_) ? last_root_ : state_[0]);
    return last_root_;
  }
  PrandtlIshlinskii::inverse_state(effective_weights_, plays(), scratch_);
  kernels::play_bank_step(target, inverse_thresholds_, scratch_);
  return kernels::dot(inverse_weights_, scratch_);
}

// sum_i (w_i + b_i) p_i(x) + hinges(p(x)) with p_i(x) = clamp(p_i, x - r_i, x + r_i): the
// creep-free part of this sample's H + K (the carry is the rest). A play moves with x (slope
// 1) where the clamp binds, else it holds; a hinge adds its slope while its play is above the
// level. The function is linear between kinks (a play's at p_i -+ r_i, a hinge's where its
// play's output crosses the level: b + r_i above p_i, b - r_i below), so the slopes are taken
// on each side of x (x sits on a kink of every moving play: there the sides differ) up to the
// nearest kinks below and above.
HysteresisCreep::Trial HysteresisCreep::trial_inner(double x) const noexcept {
  const std::span<const double> p = std::span<const double>(state_).first(play_count());
  constexpr double kInf = std::numeric_limits<double>::infinity();
  Trial t{0.0, 0.0, 0.0, -kInf, kInf};
  const auto kink = [&](double at) {
    if (at > x) t.above = std::min(t.above, at);
    if (at < x) t.below = std::max(t.below, at);
  };
  // Does the play of row i move with x just below x / just above x?
  const auto moves_down = [&](std::size_t i) {
    return x <= p[i] - thresholds_[i] || x > p[i] + thresholds_[i];
  };
  const auto moves_up = [&](std::size_t i) {
    return x >= p[i] + thresholds_[i] || x < p[i] - thresholds_[i];
  };
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double r = thresholds_[i];
    t.value += effective_weights_[i] * std::min(std::max(p[i], x - r), x + r);
    if (moves_down(i)) t.slope_down += effective_weights_[i];
    if (moves_up(i)) t.slope_up += effective_weights_[i];
    if (r > 0.0) {
      kink(p[i] - r);
      kink(p[i] + r);
    }
  }
  const PlayHinges& g = params_.hinges;
  for (std::size_t h = 0; h < hinge_rows_.size(); ++h) {
    const std::size_t i = hinge_rows_[h];
    const double r = thresholds_[i];
    const double level = g.levels[h];
    const double now = std::min(std::max(p[i], x - r), x + r);
    if (now > level) t.value += g.weights[h] * (now - level);
    if (now > level && moves_down(i)) t.slope_down += g.weights[h];
    if (now >= level && moves_up(i)) t.slope_up += g.weights[h];
    kink(level >= p[i] ? level + r : level - r);
  }
  return t;
}

double HysteresisCreep::solve_inner(double target, double start) const noexcept {
  if (!std::isfinite(target)) return target;
  double x = start;
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  double step = scale_;
  constexpr int kIterations = 100;
  for (int it = 0; it < kIterations; ++it) {
    const Trial trial = trial_inner(x);
    const double miss = trial.value - target;
    if (miss == 0.0) return x;
    if (miss < 0.0) {
      lo = x;
    } else {
      hi = x;
    }
    const bool bracketed = std::isfinite(lo) && std::isfinite(hi);
    if (bracketed && hi - lo <= 1e-12 * std::max(std::abs(lo), std::abs(hi))) break;
    // Newton with the slope on the root's side; inside the piece the function is that line,
    // so a step that stays in it lands on the root (most samples need this one evaluation).
    const double slope = miss < 0.0 ? trial.slope_up : trial.slope_down;
    double next = slope > 0.0 ? x - miss / slope : std::numeric_limits<double>::quiet_NaN();
    if (next >= trial.below && next <= trial.above) return next;
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
  last_root_ = std::numeric_limits<double>::quiet_NaN();
  std::copy(state.begin(), state.end(), state_.begin());
}

void HysteresisCreep::reset(double x) noexcept {
  last_root_ = std::numeric_limits<double>::quiet_NaN();
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
