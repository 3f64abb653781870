#include "selfsense/identification/operator_fit.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "selfsense/identification/fit_quality.hpp"
#include "selfsense/operators/typical_stack.hpp"

namespace selfsense::identification {
namespace {

using operators::HysteresisCreep;

constexpr double kTs = 1e-3;

// Field: decaying 1 Hz and 0.3 Hz sines around 1 MV/m with holds; stress: slow sine.
struct Data {
  std::vector<double> e, t, y;
};

Data make_data(const HysteresisCreep::Params& truth, double coupling, std::size_t n, double noise,
               std::uint64_t seed) {
  Data d;
  HysteresisCreep op(truth, kTs);
  op.set_history(std::vector<double>{0.0, 2e6, 0.4e6});  // remanent, not demagnetised
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  for (std::size_t k = 0; k < n; ++k) {
    const double time = static_cast<double>(k) * kTs;
    const double envelope = 0.5 + 0.5 * std::exp(-time / 20.0);
    const double hold = std::fmod(time, 10.0) > 8.0 ? 0.0 : 1.0;
    const double e = 1e6 + hold * envelope * 1e6 *
                               (0.7 * std::sin(2 * std::numbers::pi * time - 0.9) +
                                0.3 * std::sin(2 * std::numbers::pi * 0.3 * time));
    const double t = -1e7 * (1.0 + std::sin(2 * std::numbers::pi * 0.07 * time));
    d.e.push_back(e);
    d.t.push_back(t);
    d.y.push_back(op.step(e) + coupling * t + noise * n01(rng));
  }
  return d;
}

TEST(OperatorFit, LinearStructureRecoversPermittivityAndCoupling) {
  HysteresisCreep::Params linear;
  linear.hysteresis.linear_weight = 4e-8;  // eps [F/m]
  const Data d = make_data(linear, 3e-10, 20000, 0.0, 1);
  const OperatorModel m = fit_operator({d.e, {d.t}, d.y, kTs}, OperatorStructure{});
  EXPECT_NEAR(m.op.hysteresis.linear_weight, 4e-8, 1e-14);
  EXPECT_NEAR(m.linear_gains.at(0), 3e-10, 1e-16);
  EXPECT_NEAR(m.offset, 0.0, 1e-9);
}

// A typical stack's charge with creep and dead zones, and the structure fitted to it (other sizes).
HysteresisCreep::Params stack_truth() {
  operators::TypicalStackSize size;
  size.plays = 12;
  size.dead_zones = 3;
  size.eigenvalues = 4;
  return operators::typical_stack_charge(size);
}

OperatorStructure stack_structure() {
  OperatorStructure s;
  s.plays = 16;
  s.eigenvalues = 5;
  s.dead_zones = 3;
  return s;
}

TEST(OperatorFit, HysteresisCreepWithRemanentStartFitsFromTheFirstCycle) {
  const double range_guess = 0.1;
  const Data d = make_data(stack_truth(), 3e-10, 60000, 1e-4 * range_guess, 2);
  const OperatorStructure s = stack_structure();
  const OperatorModel m = fit_operator({d.e, {d.t}, d.y, kTs}, s);
  std::vector<double> y(d.y.size());
  simulate_operator(m, d.e, {d.t}, y);
  const FitQuality all = fit_quality(d.y, y);
  const FitQuality first_cycle =
      fit_quality(std::span(d.y).first(1000), std::span<const double>(y).first(1000));
  EXPECT_LT(all.nrmse, 2e-3);
  EXPECT_LT(all.max, 1e-2);
  // The remanent start is estimated: the first cycle fits nearly as well as the rest.
  EXPECT_LT(first_cycle.max, 1.5e-2);
  EXPECT_LT(first_cycle.nrmse, 5e-3);
  EXPECT_NEAR(m.linear_gains.at(0), 3e-10, 0.05 * 3e-10);
}

// A given start replaces the search: from the start the search chose, the same fit; from another
// start, a fit from that one (the diagnosis's trials take their null's start).
TEST(OperatorFit, AGivenStartIsFittedFromWithoutASearch) {
  const Data d = make_data(stack_truth(), 3e-10, 30000, 1e-5, 3);
  OperatorStructure s = stack_structure();
  const OperatorModel searched = fit_operator({d.e, {d.t}, d.y, kTs}, s);
  ASSERT_GT(searched.history.size(), 1U);  // the remanent start, not the demagnetised one
  s.start = searched.history;
  const OperatorModel given = fit_operator({d.e, {d.t}, d.y, kTs}, s);
  EXPECT_EQ(given.history, searched.history);
  EXPECT_EQ(given.op.hysteresis.weights, searched.op.hysteresis.weights);
  EXPECT_EQ(given.op.creep.weights, searched.op.creep.weights);
  EXPECT_EQ(given.linear_gains, searched.linear_gains);

  s.start = {d.e.front()};  // demagnetised: kept, and the first cycle fits worse from it
  const OperatorModel demagnetised = fit_operator({d.e, {d.t}, d.y, kTs}, s);
  EXPECT_EQ(demagnetised.history, s.start);
  std::vector<double> y_searched(d.y.size());
  std::vector<double> y_demagnetised(d.y.size());
  simulate_operator(searched, d.e, {d.t}, y_searched);
  simulate_operator(demagnetised, d.e, {d.t}, y_demagnetised);
  const auto first_cycle = [&](const std::vector<double>& y) {
    return fit_quality(std::span(d.y).first(1000), std::span<const double>(y).first(1000)).nrmse;
  };
  EXPECT_GT(first_cycle(y_demagnetised), 4.0 * first_cycle(y_searched));  // measured 8.8x
}

// The normal equations over every 4th row (weighted by 4): the same structure, about the same fit
// on every sample, and residuals in the units of every sample (the diagnosis's re-identifications
// of long records, IdentificationOptions::max_rows).
TEST(OperatorFit, EveryFourthRowFitsAboutAsWellAsEveryRow) {
  const Data d = make_data(stack_truth(), 3e-10, 60000, 1e-4 * 0.1, 4);
  OperatorStructure s = stack_structure();
  const OperatorModel every = fit_operator({d.e, {d.t}, d.y, kTs}, s);
  s.row_step = 4;
  const OperatorModel fourth = fit_operator({d.e, {d.t}, d.y, kTs}, s);
  EXPECT_NE(fourth.op.hysteresis.weights, every.op.hysteresis.weights);  // other rows, other fit
  std::vector<double> y_every(d.y.size());
  std::vector<double> y_fourth(d.y.size());
  simulate_operator(every, d.e, {d.t}, y_every);
  simulate_operator(fourth, d.e, {d.t}, y_fourth);
  const double nrmse_every = fit_quality(d.y, y_every).nrmse;
  const double nrmse_fourth = fit_quality(d.y, y_fourth).nrmse;
  EXPECT_LT(nrmse_every, 2e-3);
  EXPECT_LT(nrmse_fourth, 1.02 * nrmse_every);  // measured: equal to four digits (0.1106 %)
  EXPECT_NEAR(fourth.linear_gains.at(0), 3e-10, 0.05 * 3e-10);
}

TEST(OperatorFit, RejectsBadSignals) {
  const std::vector<double> x{1.0, 1.0, 1.0};
  const std::vector<double> y{0.0, 1.0, 2.0};
  EXPECT_THROW(static_cast<void>(fit_operator({x, {}, y, kTs}, {})), std::invalid_argument);
  const std::vector<double> x2{1.0, 2.0, 3.0};
  EXPECT_THROW(static_cast<void>(fit_operator({x2, {}, y, 0.0}, {})), std::invalid_argument);
  EXPECT_THROW(static_cast<void>(fit_operator({x2, {}, std::span(y).first(2), kTs}, {})),
               std::invalid_argument);
}

}  // namespace
}  // namespace selfsense::identification
