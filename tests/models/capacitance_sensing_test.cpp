#include "selfsense/models/capacitance_sensing.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "selfsense/identification/fit_quality.hpp"
#include "selfsense/operators/parameter_error.hpp"
#include "selfsense/plant/plant.hpp"
#include "support/stressed_stack.hpp"

namespace selfsense::models {
namespace {

TEST(CapacitanceEstimator, ConvergesToTheSlopeOfAnAffineCharacteristic) {
  CapacitanceEstimator est({0.99, 0.0, 1e-6, 0.0});
  for (int k = 0; k < 2000; ++k) {
    const double e = 1e6 + 1e4 * std::sin(0.1 * k);
    est.step(e, 2e-8 * e + 0.003);  // offset cancels in the increments
  }
  EXPECT_NEAR(est.estimate(), 2e-8, 1e-12);
}

TEST(CapacitanceEstimator, IgnoresNonFiniteSamplesAndRejectsBadParameters) {
  CapacitanceEstimator est({0.99, 2e-8, 1e-6, 0.0});
  est.step(1.0, 1.0);
  EXPECT_DOUBLE_EQ(est.step(std::nan(""), 2.0), 2e-8);
  EXPECT_THROW(CapacitanceEstimator({1.5, 0.0, 1e-6, 0.0}), operators::ParameterError);
  EXPECT_THROW(CapacitanceEstimator({0.99, 0.0, -1.0, 0.0}), operators::ParameterError);
}

// A stack at a constant bias field with a small probe sine, under a slowly varying load: the
// permittivity follows the stress (plant stress effects), so the estimated capacitance gives
// the force without any charge-balance model of the load.
TEST(CapacitanceSensing, StressFromTheEstimatedCapacitanceOfAStressedStack) {
  const plant::PlantConfig c = test::stressed_stack(10000.0, 2e-6);
  plant::Plant p(c);
  CapacitanceEstimator est({1.0 - 1.0 / 200.0, 2e-8, 1e-6, 0.0});  // memory 20 ms
  std::vector<double> cap;
  std::vector<double> stress;
  const int n = 200000;  // 20 s
  for (int k = 0; k < n; ++k) {
    const double t = k / c.sample_rate_hz;
    const double e = 1e6 + 2e4 * std::sin(2 * std::numbers::pi * 200.0 * t);
    const double f = 600.0 * std::sin(2 * std::numbers::pi * 0.25 * t);
    const plant::StepOutput out = p.step({e, f, 25.0});
    const double c_hat = est.step(out.e_meas_v_per_m, out.d_meas_c_per_m2);
    if (k >= 20000) {  // after the estimator has settled
      cap.push_back(c_hat);
      stress.push_back(out.t_pa);
    }
  }
  const std::size_t half = cap.size() / 2;
  const CapacitanceCharacteristic ch =
      fit_capacitance_characteristic(std::span(cap).first(half), std::span(stress).first(half));
  std::vector<double> t_hat;
  for (std::size_t k = half; k < cap.size(); ++k)
    t_hat.push_back(ch.stress(cap[k]));
  const auto q = identification::fit_quality(std::span(stress).subspan(half), t_hat);
  // Measured: nrmse 1.7 %, max 6.2 % of the stress range, on the second half.
  std::printf("T_hat from capacitance: nrmse %.2f %%, max %.2f %%\n", 100 * q.nrmse, 100 * q.max);
  // Measured 1.68 % and 6.16 % (docs/results.md); the bounds are about 1.3x.
  EXPECT_LT(q.nrmse, 0.022);
  EXPECT_LT(q.max, 0.08);
}

}  // namespace
}  // namespace selfsense::models
