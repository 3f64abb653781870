#include "selfsense/operators/hysteresis_creep.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <utility>

#include "selfsense/operators/kernels.hpp"
#include "selfsense/operators/parameter_error.hpp"

namespace selfsense::operators {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Levels of one play (ascending, ending with the +inf sentinel) below v, found from the guess k.
// A play moves by at most the input's step, so its segment usually stays or moves by one: that
// one step is taken without a branch, and the loops after it are rarely entered.
std::size_t levels_below(const double* levels, std::size_t k, double v) noexcept {
  k += static_cast<std::size_t>(levels[k] < v);
  k -= static_cast<std::size_t>(k > 0 && !(levels[k - 1] < v));
  while (levels[k] < v)
    ++k;
  while (k > 0 && !(levels[k - 1] < v))
    --k;
  return k;
}

// Levels at or below v, from k = levels_below(v): the slope on v's upper side counts a hinge
// at exactly v. `last` bounds it to the play's table.
std::size_t levels_at_or_below(const double* levels, std::size_t k, std::size_t last,
                               double v) noexcept {
  while (k < last && levels[k] <= v)
    ++k;
  return k;
}

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
  // Segment tables: each play's hinges sorted by level (plays without hinges: segment 0).
  if (!hinge_rows_.empty()) {
    std::vector<std::vector<std::size_t>> of_play(n);
    for (std::size_t k = 0; k < hinge_rows_.size(); ++k)
      of_play[hinge_rows_[k]].push_back(k);
    std::size_t most = 0;
    for (const auto& hinges : of_play)
      most = std::max(most, hinges.size());
    hinge_stride_ = most + 1;
    hinge_levels_.assign(n * hinge_stride_, kInf);
    segment_slopes_.assign(n * hinge_stride_, 0.0);
    segment_anchors_.assign(n * hinge_stride_, 0.0);
    segment_values_.assign(n * hinge_stride_, 0.0);
    const PlayHinges& g = params_.hinges;
    for (std::size_t i = 0; i < n; ++i) {
      std::vector<std::size_t>& hinges = of_play[i];
      std::stable_sort(hinges.begin(), hinges.end(),
                       [&](std::size_t a, std::size_t b) { return g.levels[a] < g.levels[b]; });
      const std::size_t base = i * hinge_stride_;
      for (std::size_t k = 1; k <= hinges.size(); ++k) {
        const double anchor = g.levels[hinges[k - 1]];
        hinge_levels_[base + k - 1] = anchor;
        segment_anchors_[base + k] = anchor;
        // g at the anchor and the slope above it, summed hinge by hinge (no cancellation).
        for (std::size_t j = 0; j < k; ++j) {
          segment_slopes_[base + k] += g.weights[hinges[j]];
          segment_values_[base + k] += g.weights[hinges[j]] * (anchor - g.levels[hinges[j]]);
        }
      }
    }
    segments_.assign(n, 0);
    hinge_terms_.assign(n, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
      if (!of_play[i].empty()) hinged_plays_.push_back(i);
    }
  }
  state_.assign(n + creep_weights_.size(), 0.0);
  locate_segments();
}

double HysteresisCreep::hinge_sum() const noexcept {
  return Eigen::Map<const Eigen::ArrayXd>(hinge_terms_.data(),
                                          static_cast<Eigen::Index>(hinge_terms_.size()))
      .sum();
}

// Plays without hinges keep a zero term (also at an infinite output, where 0 * inf is NaN).
void HysteresisCreep::locate_segments() noexcept {
  for (const std::size_t i : hinged_plays_) {
    segments_[i] = levels_below(hinge_levels_.data() + i * hinge_stride_, 0, state_[i]);
    hinge_terms_[i] = hinge_value(i, segments_[i], state_[i]);
  }
}

double HysteresisCreep::inner_step(double x) noexcept {
  const std::span<double> p = plays();
  const std::span<double> z = lags();
  double sum = 0.0;
  if (segments_.empty()) {
    kernels::play_bank_step(x, thresholds_, p);
    sum = kernels::dot(hysteresis_weights_, p);
  } else {
    // A held play keeps its segment and its hinges' term; only the plays that moved (those of
    // the smallest thresholds: a play moves only when every smaller one does) look theirs up.
    // Each term is a function of its play's output alone, so the sum is the same as if every
    // term were evaluated again (no drift).
    std::copy(p.begin(), p.end(), scratch_.begin());
    kernels::play_bank_step(x, thresholds_, p);
    for (const std::size_t i : hinged_plays_) {
      if (p[i] != scratch_[i]) {
        const std::size_t at = i * hinge_stride_;
        segments_[i] = levels_below(hinge_levels_.data() + at, segments_[i], p[i]);
        hinge_terms_[i] = hinge_value(i, segments_[i], p[i]);
      }
    }
    sum = kernels::dot(hysteresis_weights_, p) + hinge_sum();
  }
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
// 1) where the clamp binds, else it holds; its hinges add their segment's slope while it moves.
// The function is linear between kinks (a play's at p_i -+ r_i; a hinge's where its play's
// output crosses the level: b + r_i above p_i, b - r_i below), so the slopes are taken on each
// side of x (x sits on a kink of every moving play: there the sides differ) up to the nearest
// kinks below and above. A held play's hinge kinks lie beyond its own kinks (b >= p gives
// b + r >= p + r), so only the moving plays' nearest levels are looked at: the levels next to
// the play's output on the side it moves from (>= p moving up, < p moving down), and on the
// input's play (r = 0, no kinks of its own) those next to x.
HysteresisCreep::Trial HysteresisCreep::trial_inner(double x) noexcept {
  const std::span<const double> p = std::span<const double>(state_).first(play_count());
  const std::span<const double> w(effective_weights_);
  const std::size_t last = hinge_stride_ - 1;
  Trial t{0.0, 0.0, 0.0, -kInf, kInf};
  {  // The input's play: p_0(x) = x, moving on both sides.
    const double* levels = hinge_levels_.data();
    const std::size_t below = levels_below(levels, segments_[0], x);
    const std::size_t upto = levels_at_or_below(levels, below, last, x);
    scratch_[0] = w[0] * x + hinge_value(0, below, x);
    t.slope_down = w[0] + segment_slopes_[below];
    t.slope_up = w[0] + segment_slopes_[upto];
    t.above = levels[upto];
    if (below > 0) t.below = levels[below - 1];
  }
  for (std::size_t i = 1; i < p.size(); ++i) {
    const double r = thresholds_[i];
    const double lower = p[i] - r;
    const double upper = p[i] + r;
    const double* levels = hinge_levels_.data() + i * hinge_stride_;
    const std::size_t at = i * hinge_stride_;
    if (x >= upper) {  // moving up with x (held just below x when x == upper)
      const double now = x - r;
      const std::size_t below = levels_below(levels, segments_[i], now);
      const std::size_t upto = levels_at_or_below(levels, below, last, now);
      scratch_[i] = w[i] * now + hinge_value(i, below, now);
      t.slope_up += w[i] + segment_slopes_[at + upto];
      if (x > upper) t.slope_down += w[i] + segment_slopes_[at + below];
      t.below = std::max(t.below, upper < x ? upper : lower);
      t.above = std::min(t.above, levels[upto] + r);
      if (below > 0 && levels[below - 1] >= p[i])
        t.below = std::max(t.below, levels[below - 1] + r);
    } else if (x <= lower) {  // moving down with x (held just above x when x == lower)
      const double now = x + r;
      const std::size_t below = levels_below(levels, segments_[i], now);
      const std::size_t upto = levels_at_or_below(levels, below, last, now);
      scratch_[i] = w[i] * now + hinge_value(i, below, now);
      t.slope_down += w[i] + segment_slopes_[at + below];
      if (x < lower) t.slope_up += w[i] + segment_slopes_[at + upto];
      t.above = std::min(t.above, lower > x ? lower : upper);
      if (levels[upto] < p[i]) t.above = std::min(t.above, levels[upto] - r);
      if (below > 0) t.below = std::max(t.below, levels[below - 1] - r);
    } else {  // held
      scratch_[i] = w[i] * p[i] + hinge_terms_[i];
      t.below = std::max(t.below, lower);
      t.above = std::min(t.above, upper);
    }
  }
  t.value =
      Eigen::Map<const Eigen::ArrayXd>(scratch_.data(), static_cast<Eigen::Index>(p.size())).sum();
  return t;
}

double HysteresisCreep::solve_inner(double target, double start) noexcept {
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
  return shape_.evaluate(kernels::dot(hysteresis_weights_, all.first(play_count())) + hinge_sum() +
                         kernels::dot(creep_weights_, all.subspan(play_count())));
}

void HysteresisCreep::set_state(std::span<const double> state) noexcept {
  assert(state.size() == state_.size());
  last_root_ = std::numeric_limits<double>::quiet_NaN();
  std::copy(state.begin(), state.end(), state_.begin());
  locate_segments();
}

void HysteresisCreep::reset(double x) noexcept {
  last_root_ = std::numeric_limits<double>::quiet_NaN();
  std::fill(state_.begin(), state_.end(), x);
  locate_segments();
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
  locate_segments();
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
