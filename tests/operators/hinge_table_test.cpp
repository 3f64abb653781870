// The hinge table (HysteresisCreep evaluates its hinges row by row over all plays, see the
// header) against a plain reference: one hinge at a time, in the order listed, with the
// branches of the per-hinge evaluation it replaced. Forward outputs and the inverse's roots
// must agree to 1e-12 relative over random hinges and random inputs (fixed seeds).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <random>
#include <span>
#include <vector>

#include "selfsense/operators/hysteresis_creep.hpp"
#include "selfsense/operators/typical_stack.hpp"
#include "support/random_walk.hpp"

namespace selfsense::operators {
namespace {

constexpr double kTs = 5e-5;
constexpr double kInf = std::numeric_limits<double>::infinity();

// H + K + S with plain loops: plays, hinges one by one, creep lags; the inverse by the
// safeguarded Newton iteration on per-hinge slopes and kinks.
class Reference {
 public:
  Reference(const HysteresisCreep::Params& p, double ts)
      : p_(p), shape_(p.superposition), shape_inverse_(shape_.inverse()) {
    r_.push_back(0.0);
    r_.insert(r_.end(), p.hysteresis.thresholds.begin(), p.hysteresis.thresholds.end());
    r_.insert(r_.end(), p.creep.thresholds.begin(), p.creep.thresholds.end());
    r_.insert(r_.end(), p.hinges.thresholds.begin(), p.hinges.thresholds.end());
    std::sort(r_.begin(), r_.end());
    r_.erase(std::unique(r_.begin(), r_.end()), r_.end());
    w_.assign(r_.size(), 0.0);
    w_[0] = p.hysteresis.linear_weight;
    for (std::size_t i = 0; i < p.hysteresis.thresholds.size(); ++i)
      w_[row(p.hysteresis.thresholds[i])] = p.hysteresis.weights[i];
    effective_ = w_;
    const std::size_t cols = p.creep.eigenvalues.size();
    for (std::size_t i = 0; i < p.creep.thresholds.size(); ++i) {
      for (std::size_t j = 0; j < cols; ++j) {
        const double a = -std::expm1(-p.creep.eigenvalues[j] * ts);
        const double c = p.creep.weights[i * cols + j];
        gain_.push_back(a);
        lag_row_.push_back(row(p.creep.thresholds[i]));
        effective_[lag_row_.back()] += c * a;
      }
    }
    plays_.assign(r_.size(), 0.0);
    lags_.assign(gain_.size(), 0.0);
  }

  double step(double x) {
    double sum = 0.0;
    for (std::size_t i = 0; i < r_.size(); ++i) {
      plays_[i] = std::min(std::max(plays_[i], x - r_[i]), x + r_[i]);
      sum += w_[i] * plays_[i];
    }
    for (std::size_t h = 0; h < p_.hinges.thresholds.size(); ++h) {
      sum += p_.hinges.weights[h] *
             std::max(plays_[row(p_.hinges.thresholds[h])] - p_.hinges.levels[h], 0.0);
    }
    for (std::size_t e = 0; e < lags_.size(); ++e) {
      lags_[e] += gain_[e] * (plays_[lag_row_[e]] - lags_[e]);
      sum += p_.creep.weights[e] * lags_[e];
    }
    return shape_.evaluate(sum);
  }

  double input_for(double y) {
    double carry = 0.0;
    for (std::size_t e = 0; e < lags_.size(); ++e)
      carry += p_.creep.weights[e] * (1.0 - gain_[e]) * lags_[e];
    const double target = shape_inverse_.evaluate(y) - carry;
    last_root_ = solve(target, std::isfinite(last_root_) ? last_root_ : plays_[0]);
    return last_root_;
  }

 private:
  struct Trial {
    double value{0.0};
    double slope_down{0.0};
    double slope_up{0.0};
    double below{-kInf};
    double above{kInf};
  };

  std::size_t row(double r) const {
    return static_cast<std::size_t>(std::lower_bound(r_.begin(), r_.end(), r) - r_.begin());
  }

  Trial trial(double x) const {
    Trial t;
    const auto kink = [&](double at) {
      if (at > x) t.above = std::min(t.above, at);
      if (at < x) t.below = std::max(t.below, at);
    };
    const auto moves_down = [&](std::size_t i) {
      return x <= plays_[i] - r_[i] || x > plays_[i] + r_[i];
    };
    const auto moves_up = [&](std::size_t i) {
      return x >= plays_[i] + r_[i] || x < plays_[i] - r_[i];
    };
    for (std::size_t i = 0; i < r_.size(); ++i) {
      t.value += effective_[i] * std::min(std::max(plays_[i], x - r_[i]), x + r_[i]);
      if (moves_down(i)) t.slope_down += effective_[i];
      if (moves_up(i)) t.slope_up += effective_[i];
      if (r_[i] > 0.0) {
        kink(plays_[i] - r_[i]);
        kink(plays_[i] + r_[i]);
      }
    }
    for (std::size_t h = 0; h < p_.hinges.thresholds.size(); ++h) {
      const std::size_t i = row(p_.hinges.thresholds[h]);
      const double level = p_.hinges.levels[h];
      const double c = p_.hinges.weights[h];
      const double now = std::min(std::max(plays_[i], x - r_[i]), x + r_[i]);
      if (now > level) t.value += c * (now - level);
      if (now > level && moves_down(i)) t.slope_down += c;
      if (now >= level && moves_up(i)) t.slope_up += c;
      kink(level >= plays_[i] ? level + r_[i] : level - r_[i]);
    }
    return t;
  }

  double solve(double target, double x) const {
    const double scale = std::max(r_.back(), 1e-300);
    double lo = -kInf;
    double hi = kInf;
    double step = scale;
    for (int it = 0; it < 100; ++it) {
      const Trial t = trial(x);
      const double miss = t.value - target;
      if (miss == 0.0) return x;
      (miss < 0.0 ? lo : hi) = x;
      const bool bracketed = std::isfinite(lo) && std::isfinite(hi);
      if (bracketed && hi - lo <= 1e-12 * std::max(std::abs(lo), std::abs(hi))) break;
      const double slope = miss < 0.0 ? t.slope_up : t.slope_down;
      double next = slope > 0.0 ? x - miss / slope : std::numeric_limits<double>::quiet_NaN();
      if (next >= t.below && next <= t.above) return next;
      if (std::abs(next - x) <= 1e-12 * std::max(std::abs(x), scale)) return next;
      if (!(next > lo && next < hi)) {
        if (bracketed) {
          next = 0.5 * (lo + hi);
        } else {
          next = miss < 0.0 ? x + step : x - step;
          step *= 2.0;
        }
      }
      x = next;
    }
    return std::isfinite(lo) && std::isfinite(hi) ? 0.5 * (lo + hi) : x;
  }

  HysteresisCreep::Params p_;
  DeadZoneSuperposition shape_;
  DeadZoneSuperposition shape_inverse_;
  std::vector<double> r_;
  std::vector<double> w_;
  std::vector<double> effective_;
  std::vector<double> gain_;
  std::vector<std::size_t> lag_row_;
  std::vector<double> plays_;
  std::vector<double> lags_;
  double last_root_{std::numeric_limits<double>::quiet_NaN()};
};

// The typical charge operator (creep on 2 plays) with 0..8 hinges on each play and the input,
// in random order (not sorted by play or level); weights of either sign, small enough that the
// operator stays increasing (a unique root for the inverse).
HysteresisCreep::Params random_hinges(std::uint64_t seed) {
  TypicalStackSize size;
  size.plays = 16;
  size.dead_zones = 4;
  size.eigenvalues = 4;
  size.creep_plays = 2;
  HysteresisCreep::Params p = typical_stack_charge(size);
  std::mt19937_64 rng(seed);
  std::vector<double> r{0.0};
  r.insert(r.end(), p.hysteresis.thresholds.begin(), p.hysteresis.thresholds.end());
  std::uniform_int_distribution<int> count(0, 8);
  std::uniform_real_distribution<double> level(-0.2e6, 2.2e6);
  std::uniform_real_distribution<double> weight(-0.04, 0.1);
  for (const double threshold : r) {
    for (int k = count(rng); k > 0; --k) {
      p.hinges.thresholds.push_back(threshold);
      p.hinges.levels.push_back(level(rng));
      p.hinges.weights.push_back(weight(rng) * p.hysteresis.linear_weight);
    }
  }
  std::vector<std::size_t> order(p.hinges.thresholds.size());
  for (std::size_t h = 0; h < order.size(); ++h)
    order[h] = h;
  std::shuffle(order.begin(), order.end(), rng);
  PlayHinges shuffled;
  for (const std::size_t h : order) {
    shuffled.thresholds.push_back(p.hinges.thresholds[h]);
    shuffled.levels.push_back(p.hinges.levels[h]);
    shuffled.weights.push_back(p.hinges.weights[h]);
  }
  p.hinges = shuffled;
  return p;
}

// |a - b| within 1e-12 of b's magnitude, or of `floor` near zero.
bool close(double a, double b, double floor) {
  return std::abs(a - b) <= 1e-12 * std::max(std::abs(b), floor);
}

TEST(HingeTable, ForwardMatchesThePerHingeSum) {
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    const HysteresisCreep::Params p = random_hinges(seed);
    HysteresisCreep op(p, kTs);
    Reference ref(p, kTs);
    const std::vector<double> e = test::random_walk(20000, -0.1e6, 2.1e6, 3e4, seed);
    std::size_t bad = 0;
    double worst = 0.0;
    for (const double x : e) {
      const double want = ref.step(x);
      const double got = op.step(x);
      worst = std::max(worst, std::abs(got - want) / std::max(std::abs(want), 1e-3));
      if (!close(got, want, 1e-3)) ++bad;
    }
    EXPECT_EQ(bad, 0U) << "seed " << seed << ", worst relative difference " << worst;
  }
}

TEST(HingeTable, InverseMatchesThePerHingeSolve) {
  for (std::uint64_t seed = 11; seed <= 18; ++seed) {
    const HysteresisCreep::Params p = random_hinges(seed);
    HysteresisCreep op(p, kTs);
    Reference ref(p, kTs);
    Reference twin(p, kTs);  // makes reachable targets
    // Small and large steps: the large ones cross several levels of a play in one sample.
    const double step = seed % 2 == 0 ? 3e4 : 2e5;
    const std::vector<double> e = test::random_walk(20000, -0.1e6, 2.1e6, step, seed);
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> feedback(0.0, 2e3);
    std::size_t bad = 0;
    for (const double x : e) {
      const double y = twin.step(x);
      const double root = ref.input_for(y);
      if (!close(op.input_for(y), root, 2e6)) ++bad;
      // Advance both with an input beside the root, as a loop's feedback does: the next solve
      // starts from the root, not from the applied input.
      const double applied = root + feedback(rng);
      if (!close(op.step(applied), ref.step(applied), 1e-3)) ++bad;
    }
    EXPECT_EQ(bad, 0U) << "seed " << seed;
  }
}

}  // namespace
}  // namespace selfsense::operators
