#include "selfsense/operators/hysteresis_creep.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "selfsense/operators/threshold_creep.hpp"
#include "selfsense/operators/typical_stack.hpp"
#include "support/random_walk.hpp"

namespace selfsense::operators {
namespace {

constexpr double kTs = 1e-4;

TypicalStackSize with_creep_plays() {
  TypicalStackSize size;
  size.plays = 24;
  size.dead_zones = 6;
  size.eigenvalues = 6;
  size.creep_plays = 3;
  return size;
}

// A desired strain: steps with holds, then a decaying sine (nested minor loops).
std::vector<double> desired_strain(std::size_t n) {
  std::vector<double> y(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * kTs;
    const double level = 2e-4 * std::floor(t / 0.5);
    const double ring = 3e-4 * std::exp(-t / 1.5) * std::sin(2.0 * std::numbers::pi * 7.0 * t);
    y[k] = std::min(level, 8e-4) + 3e-4 + ring;
  }
  return y;
}

TEST(HysteresisCreep, CompensatorMakesTheOperatorFollowTheDesiredTrajectory) {
  const HysteresisCreep::Params params = typical_stack_strain(with_creep_plays());
  HysteresisCreep actuator(params, kTs);
  HysteresisCreepCompensator feedforward(HysteresisCreep(params, kTs), -1e7, 1e7);
  const std::vector<double> desired = desired_strain(60000);
  const double range = *std::max_element(desired.begin(), desired.end()) -
                       *std::min_element(desired.begin(), desired.end());
  double worst = 0.0;
  for (const double yd : desired) {
    const double field = feedforward.step(yd);
    worst = std::max(worst, std::abs(actuator.step(field) - yd));
  }
  EXPECT_LE(worst, 1e-6 * range);
  EXPECT_EQ(feedforward.saturation_count(), 0U);
}

TEST(HysteresisCreep, InverseStepThenOutputGivesTheTarget) {
  HysteresisCreep op(typical_stack_charge(with_creep_plays()), kTs);
  const std::vector<double> e = test::random_walk(20000, 0.0, 2e6, 2e4, 21);
  // Targets reachable by construction: the output of a twin driven with e.
  HysteresisCreep twin(typical_stack_charge(with_creep_plays()), kTs);
  for (const double v : e) {
    const double target = twin.step(v);
    const double x = op.inverse_step(target);
    ASSERT_NEAR(x, v, 1e-6 * 2e6);
    ASSERT_NEAR(op.output(), target, 1e-12);
  }
}

TEST(HysteresisCreep, CompensatorSaturatesAndKeepsTheModelTrue) {
  const HysteresisCreep::Params params = typical_stack_strain();
  HysteresisCreepCompensator feedforward(HysteresisCreep(params, kTs), 0.0, 1e6);
  HysteresisCreep actuator(params, kTs);
  double last = 0.0;
  for (int k = 0; k < 100; ++k) {
    const double field = feedforward.step(1.4e-3);  // needs more than 1e6 V/m
    EXPECT_LE(field, 1e6);
    last = actuator.step(field);
  }
  EXPECT_EQ(feedforward.saturation_count(), 100U);
  EXPECT_NEAR(feedforward.model().output(), last, 1e-15);
}

TEST(HysteresisCreep, NonlinearCreepFormIsHysteresisPlusCreepOfHysteresis) {
  // with_nonlinear_creep builds S[H + L[H]] (paper eq. 26-29) from its three parts.
  const PrandtlIshlinskii::Params h{0.4, {0.2, 0.6, 1.0}, {0.3, 0.2, 0.1}};
  const DeadZoneSuperposition::Params s{1.0, {1.5}, {-0.4}, {}, {}};
  const LinearCreep::Params l{{100.0, 1.0}, {0.05, 0.03}};
  HysteresisCreep op(HysteresisCreep::with_nonlinear_creep(h, s, l), 1e-3);
  PrandtlIshlinskii pi(h);
  LinearCreep creep(l, 1e-3);
  const DeadZoneSuperposition shape(s);
  for (const double v : test::random_walk(20000, -2.0, 2.0, 0.05, 13)) {
    const double hv = pi.step(v);
    ASSERT_NEAR(op.step(v), shape.evaluate(hv + creep.step(hv)), 1e-12);
  }
}

TEST(HysteresisCreep, TypicalStackHasRealisticHysteresisAndCreep) {
  HysteresisCreep op(typical_stack_strain(), 1e-3);
  // Slow 0 -> 2e6 -> 0 triangle: loop width at mid-field relative to the stroke.
  const std::vector<double> e = test::through({0.0, 2e6, 0.0}, 1000);
  std::vector<double> s(e.size());
  op.apply(e, s);
  const double stroke = s[1000] - s[0];
  const double width = s[1500] - s[500];
  EXPECT_GT(width / stroke, 0.08);
  EXPECT_LT(width / stroke, 0.2);
  EXPECT_GT(stroke, 1.2e-3);
  EXPECT_LT(stroke, 1.8e-3);
}

// The typical charge operator with hinges on three of its plays (and the input): a Preisach
// operator whose density grows towards high bias.
HysteresisCreep::Params with_hinges() {
  HysteresisCreep::Params p = typical_stack_charge(with_creep_plays());
  const double w0 = p.hysteresis.linear_weight;
  const std::vector<double>& r = p.hysteresis.thresholds;
  p.hinges.thresholds = {0.0, r[2], r[2], r[8], r[15]};
  p.hinges.levels = {1.2e6, 0.6e6, 1.3e6, 1.0e6, 1.1e6};
  p.hinges.weights = {0.3 * w0, 0.2 * w0, -0.1 * w0, 0.15 * w0, 0.1 * w0};
  return p;
}

TEST(HysteresisCreep, HingesAddAPiecewiseLinearFunctionOfTheirPlays) {
  HysteresisCreep::Params p = with_hinges();
  p.superposition = {};  // S = identity: the output is H + K itself
  HysteresisCreep::Params plain = p;
  plain.hinges = {};
  HysteresisCreep op(p, kTs);
  HysteresisCreep pi(plain, kTs);
  // Plays of the hinges' thresholds, stepped alongside: max(x - r, min(x + r, p)).
  std::vector<double> plays(p.hinges.thresholds.size(), 0.0);
  for (const double v : test::random_walk(20000, 0.0, 2e6, 2e4, 5)) {
    double expected = pi.step(v);
    for (std::size_t h = 0; h < plays.size(); ++h) {
      const double r = p.hinges.thresholds[h];
      plays[h] = std::min(std::max(plays[h], v - r), v + r);
      expected += p.hinges.weights[h] * std::max(plays[h] - p.hinges.levels[h], 0.0);
    }
    ASSERT_NEAR(op.step(v), expected, 1e-12 * std::abs(expected) + 1e-18);
    ASSERT_NEAR(op.output(), expected, 1e-12 * std::abs(expected) + 1e-18);
  }
}

TEST(HysteresisCreep, InverseWithHingesRecoversTheInput) {
  HysteresisCreep op(with_hinges(), kTs);
  HysteresisCreep twin(with_hinges(), kTs);
  for (const double v : test::random_walk(20000, 0.0, 2e6, 2e4, 23)) {
    const double target = twin.step(v);
    const double x = op.inverse_step(target);
    ASSERT_NEAR(x, v, 1e-6 * 2e6);
    ASSERT_NEAR(op.output(), target, 1e-9 * std::abs(target) + 1e-15);
  }
}

TEST(HysteresisCreep, CompensatorWithHingesFollowsLargeSteps) {
  HysteresisCreepCompensator feedforward(HysteresisCreep(with_hinges(), kTs), -1e7, 1e7);
  HysteresisCreep actuator(with_hinges(), kTs);
  HysteresisCreep reference(with_hinges(), kTs);
  // Reachable targets with jumps of up to the whole range between samples.
  for (const double v : {0.0, 2e6, 0.1e6, 1.7e6, 0.9e6, 1.0e6, 0.0, 1.95e6}) {
    const double yd = reference.step(v);
    ASSERT_NEAR(actuator.step(feedforward.step(yd)), yd, 1e-9 * std::abs(yd));
  }
  EXPECT_EQ(feedforward.saturation_count(), 0U);
}

// In a loop the feedforward's operator advances with the command applied (feedforward plus
// feedback), not with its own root: every solve starts at the previous root, away from the
// applied input, and must still land on this sample's root (checked on a copy of the operator).
TEST(HysteresisCreep, InverseWithHingesIsExactWhenTheAppliedInputIsAnother) {
  HysteresisCreep op(with_hinges(), kTs);
  HysteresisCreep reference(with_hinges(), kTs);
  const std::vector<double> wanted = test::random_walk(20000, 0.0, 2e6, 2e4, 29);
  const std::vector<double> feedback = test::random_walk(20000, -3e5, 3e5, 1e4, 31);
  for (std::size_t k = 0; k < wanted.size(); ++k) {
    const double target = reference.step(wanted[k]);
    const double x = op.input_for(target);
    HysteresisCreep check = op;
    ASSERT_NEAR(check.step(x), target, 1e-9 * std::abs(target) + 1e-15) << "sample " << k;
    static_cast<void>(op.step(x + feedback[k]));
  }
}

TEST(HysteresisCreep, StateSaveAndRestore) {
  HysteresisCreep op(typical_stack_strain(with_creep_plays()), kTs);
  const std::vector<double> e = test::random_walk(4000, 0.0, 2e6, 3e4, 17);
  for (std::size_t k = 0; k < 2000; ++k)
    op.step(e[k]);
  const std::vector<double> saved(op.state().begin(), op.state().end());
  std::vector<double> first;
  for (std::size_t k = 2000; k < e.size(); ++k)
    first.push_back(op.step(e[k]));
  op.set_state(saved);
  for (std::size_t k = 2000; k < e.size(); ++k)
    ASSERT_EQ(op.step(e[k]), first[k - 2000]);
}

}  // namespace
}  // namespace selfsense::operators
