#include "selfsense/operators/prandtl_ishlinskii.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "selfsense/operators/modified_prandtl_ishlinskii.hpp"
#include "support/random_walk.hpp"

namespace selfsense::operators {
namespace {

PrandtlIshlinskii::Params sample_pi(std::size_t n) {
  PrandtlIshlinskii::Params p;
  p.linear_weight = 0.6;
  for (std::size_t i = 1; i <= n; ++i) {
    p.thresholds.push_back(0.1 * static_cast<double>(i));
    // Mixed signs with positive partial sums: still invertible.
    p.weights.push_back(i % 5 == 0 ? -0.02 : 0.3 / static_cast<double>(i));
  }
  return p;
}

DeadZoneSuperposition::Params sample_shape() {
  DeadZoneSuperposition::Params s;
  s.linear_weight = 1.1;
  s.upper_thresholds = {0.5, 1.0, 1.6};
  s.upper_weights = {-0.2, -0.3, 0.15};
  s.lower_thresholds = {-0.4, -1.2};
  s.lower_weights = {0.3, -0.5};
  return s;
}

double max_abs(const std::vector<double>& v) {
  double m = 0.0;
  for (const double x : v)
    m = std::max(m, std::abs(x));
  return m;
}

// Output of the operator at the end of an input signal, from the demagnetised state.
double final_output(const PrandtlIshlinskii::Params& params, const std::vector<double>& x) {
  PrandtlIshlinskii h(params);
  double y = 0.0;
  for (const double v : x)
    y = h.step(v);
  return y;
}

TEST(PrandtlIshlinskii, RateIndependent) {
  // The same path sampled 3 and 101 times per segment (a 34-fold change of rate): equal
  // outputs at every turning point and at every common sample instant of the path.
  const std::vector<double> turning = {0.0, 1.5, -0.4, 0.9, 0.2, 1.8, -1.0, 0.3};
  const std::vector<double> coarse = test::through(turning, 3);
  const std::vector<double> dense = test::through(turning, 99);
  PrandtlIshlinskii slow(sample_pi(20));
  PrandtlIshlinskii fast(sample_pi(20));
  std::vector<double> y_coarse(coarse.size());
  std::vector<double> y_dense(dense.size());
  slow.apply(coarse, y_coarse);
  fast.apply(dense, y_dense);
  for (std::size_t k = 0; k < coarse.size(); ++k) {
    EXPECT_NEAR(y_coarse[k], y_dense[k * 33], 1e-12) << "sample " << k;
  }
}

TEST(PrandtlIshlinskii, WipingOut) {
  // A minor loop inside (-0.2, 1.0) is erased once the input exceeds its earlier maximum.
  const PrandtlIshlinskii::Params params = sample_pi(20);
  const double with_minor =
      final_output(params, test::through({0.0, 1.0, -0.5, 0.6, 0.1, 1.4}, 50));
  const double without = final_output(params, test::through({0.0, 1.0, -0.5, 1.4}, 50));
  EXPECT_NEAR(with_minor, without, 1e-12);
  // And the minor loop does matter before it is wiped out.
  const double inside_minor =
      final_output(params, test::through({0.0, 1.0, -0.5, 0.6, 0.1, 0.5}, 50));
  const double inside_plain = final_output(params, test::through({0.0, 1.0, -0.5, 0.5}, 50));
  EXPECT_GT(std::abs(inside_minor - inside_plain), 1e-3);
}

TEST(PrandtlIshlinskii, MinorLoopsAreCongruent) {
  // Two different histories, then the same cycle between 0.2 and 0.7: the loops differ by a
  // constant shift only (the PI congruency property).
  const PrandtlIshlinskii::Params params = sample_pi(20);
  const std::vector<double> cycle = test::through({0.2, 0.7, 0.2}, 40);
  auto loop_after = [&](const std::vector<double>& history) {
    PrandtlIshlinskii h(params);
    for (const double v : history)
      h.step(v);
    // One settling cycle, then record.
    for (const double v : cycle)
      h.step(v);
    std::vector<double> y(cycle.size());
    h.apply(cycle, y);
    return y;
  };
  const std::vector<double> a = loop_after(test::through({0.0, 1.5, 0.2}, 30));
  const std::vector<double> b = loop_after(test::through({0.0, -1.2, 0.9, 0.2}, 30));
  const double shift = a.front() - b.front();
  EXPECT_GT(std::abs(shift), 1e-3);  // different histories give different levels
  for (std::size_t k = 0; k < a.size(); ++k)
    EXPECT_NEAR(a[k] - b[k], shift, 1e-12);
}

TEST(PrandtlIshlinskii, InverseRoundTripOnRandomWalk) {
  const PrandtlIshlinskii::Params params = sample_pi(32);
  const std::vector<double> x = test::random_walk(100000, -4.0, 4.0, 0.05, 11);
  PrandtlIshlinskii h(params);
  // Start from a remanent state, not from zero.
  for (const double v : test::through({0.0, 3.0, -1.0, 0.5}, 20))
    h.step(v);
  PrandtlIshlinskii h_inv = h.inverse();
  double worst = 0.0;
  for (const double v : x)
    worst = std::max(worst, std::abs(h_inv.step(h.step(v)) - v));
  EXPECT_LE(worst, 1e-9 * max_abs(x));
}

TEST(PrandtlIshlinskii, InverseIsAgainAPrandtlIshlinskiiOperator) {
  PrandtlIshlinskii h(sample_pi(8));
  const PrandtlIshlinskii::Params inv = h.inverse().params();
  EXPECT_DOUBLE_EQ(inv.linear_weight, 1.0 / 0.6);
  EXPECT_TRUE(inv.is_valid(nullptr));
  // Its inverse is the original operator.
  const PrandtlIshlinskii::Params back = PrandtlIshlinskii(inv).inverse().params();
  const PrandtlIshlinskii::Params orig = sample_pi(8);
  for (std::size_t i = 0; i < orig.weights.size(); ++i) {
    EXPECT_NEAR(back.weights[i], orig.weights[i], 1e-12);
    EXPECT_NEAR(back.thresholds[i], orig.thresholds[i], 1e-12);
  }
}

TEST(ModifiedPrandtlIshlinskii, InverseRoundTripOnRandomWalk) {
  ModifiedPrandtlIshlinskii gamma(PrandtlIshlinskii(sample_pi(32)),
                                  DeadZoneSuperposition(sample_shape()));
  for (const double v : test::through({0.0, -2.0, 1.0}, 20))
    gamma.step(v);
  ModifiedPrandtlIshlinskiiInverse gamma_inv = gamma.inverse();
  const std::vector<double> x = test::random_walk(100000, -4.0, 4.0, 0.05, 12);
  double worst = 0.0;
  for (const double v : x)
    worst = std::max(worst, std::abs(gamma_inv.step(gamma.step(v)) - v));
  EXPECT_LE(worst, 1e-9 * max_abs(x));
}

TEST(ModifiedPrandtlIshlinskii, LoopsAreAsymmetric) {
  ModifiedPrandtlIshlinskii gamma(PrandtlIshlinskii(sample_pi(20)),
                                  DeadZoneSuperposition(sample_shape()));
  std::vector<double> y;
  for (const double v : test::through({0.0, 2.0, -2.0, 2.0}, 100))
    y.push_back(gamma.step(v));
  const double top = *std::max_element(y.begin(), y.end());
  const double bottom = *std::min_element(y.begin(), y.end());
  EXPECT_GT(std::abs(top + bottom), 0.05 * (top - bottom));  // not point-symmetric
}

TEST(PrandtlIshlinskii, StateSaveAndRestoreReproducesOutput) {
  PrandtlIshlinskii h(sample_pi(16));
  const std::vector<double> x = test::random_walk(2000, -2.0, 2.0, 0.1, 3);
  for (std::size_t k = 0; k < 1000; ++k)
    h.step(x[k]);
  const std::vector<double> saved(h.state().begin(), h.state().end());
  std::vector<double> first;
  for (std::size_t k = 1000; k < x.size(); ++k)
    first.push_back(h.step(x[k]));
  h.set_state(saved);
  for (std::size_t k = 1000; k < x.size(); ++k)
    ASSERT_EQ(h.step(x[k]), first[k - 1000]);
}

}  // namespace
}  // namespace selfsense::operators
