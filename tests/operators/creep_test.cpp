#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "selfsense/operators/linear_creep.hpp"
#include "selfsense/operators/threshold_creep.hpp"
#include "support/random_walk.hpp"

namespace selfsense::operators {
namespace {

LinearCreep::Params sample_creep() {
  return {log_spaced_eigenvalues(1000.0, 0.01, 6), {0.01, 0.02, 0.015, 0.03, 0.01, 0.02}};
}

TEST(LinearCreep, StepResponseIsTheAnalyticSumOfExponentials) {
  const double ts = 1e-4;
  const LinearCreep::Params params = sample_creep();
  LinearCreep creep(params, ts);
  // Unit step applied just after t_{-1}: sample k lies (k + 1) Ts after the step.
  for (std::size_t k = 0; k < 200000; ++k) {
    const double y = creep.step(1.0);
    const double t = static_cast<double>(k + 1) * ts;
    ASSERT_NEAR(y, LinearCreep::step_response(params, t), 1e-12) << "k = " << k;
  }
}

TEST(LinearCreep, GainsAndEquilibrium) {
  LinearCreep creep(sample_creep(), 1e-3);
  EXPECT_NEAR(creep.static_gain(), 0.105, 1e-15);
  EXPECT_GT(creep.instant_gain(), 0.0);
  EXPECT_LT(creep.instant_gain(), creep.static_gain());
  creep.reset(2.0);
  EXPECT_NEAR(creep.step(2.0), 0.21, 1e-15);  // settled: static gain times input
}

TEST(LinearCreep, LogSpacedEigenvaluesOnePerDecade) {
  const std::vector<double> l = log_spaced_eigenvalues(1e4, 1e-2, 7);
  ASSERT_EQ(l.size(), 7U);
  for (std::size_t j = 0; j < l.size(); ++j) {
    EXPECT_NEAR(std::log10(l[j]), 4.0 - static_cast<double>(j), 1e-12);
  }
}

TEST(NonlinearCreep, EqualsThresholdCreepWithRankOneWeights) {
  // Paper eq. (28): K = L[H[x]] is a sum of creep elements on the PI's plays.
  PrandtlIshlinskii::Params h{0.5, {0.2, 0.5, 0.9}, {0.3, 0.2, 0.1}};
  const double ts = 1e-3;
  NonlinearCreep k(PrandtlIshlinskii(h), LinearCreep(sample_creep(), ts));
  ThresholdCreep elements(k.as_threshold_creep(), ts);
  const std::vector<double> x = test::random_walk(20000, -2.0, 2.0, 0.05, 5);
  for (const double v : x)
    ASSERT_NEAR(k.step(v), elements.step(v), 1e-12);
}

TEST(ThresholdCreep, CreepDependsOnHistoryLikeHysteresis) {
  // After the same final input, creep differs with the direction of approach.
  ThresholdCreep::Params p{{0.0, 0.5}, {10.0, 1.0}, {0.0, 0.0, 0.4, 0.4}};
  ThresholdCreep from_below(p, 1e-3);
  ThresholdCreep from_above(p, 1e-3);
  for (const double v : test::through({0.0, 1.0}, 100))
    from_below.step(v);
  for (const double v : test::through({0.0, 2.0, 1.0}, 100))
    from_above.step(v);
  double a = 0.0;
  double b = 0.0;
  for (int k = 0; k < 20000; ++k) {
    a = from_below.step(1.0);
    b = from_above.step(1.0);
  }
  EXPECT_NEAR(a, 0.8 * 0.5, 1e-6);  // play at 0.5 below
  EXPECT_NEAR(b, 0.8 * 1.5, 1e-6);  // play at 1.5 above
}

TEST(ThresholdCreep, StateSaveAndRestore) {
  ThresholdCreep c({{0.0, 0.3}, {50.0, 2.0}, {0.1, 0.2, 0.3, 0.4}}, 1e-3);
  const std::vector<double> x = test::random_walk(3000, -1.0, 1.0, 0.05, 9);
  for (std::size_t k = 0; k < 1500; ++k)
    c.step(x[k]);
  const std::vector<double> saved(c.state().begin(), c.state().end());
  std::vector<double> first;
  for (std::size_t k = 1500; k < x.size(); ++k)
    first.push_back(c.step(x[k]));
  c.set_state(saved);
  for (std::size_t k = 1500; k < x.size(); ++k)
    ASSERT_EQ(c.step(x[k]), first[k - 1500]);
}

}  // namespace
}  // namespace selfsense::operators
