#include "selfsense/models/stress_hysteresis.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "selfsense/identification/fit_quality.hpp"
#include "selfsense/identification/stress_hysteresis_fit.hpp"
#include "selfsense/identification/transducer_fit.hpp"
#include "selfsense/models/bracketed_solver.hpp"
#include "selfsense/models/reconstructor.hpp"
#include "selfsense/plant/plant.hpp"
#include "support/stressed_stack.hpp"

namespace selfsense::models {
namespace {

using identification::defaults_for;
using identification::fit_stress_hysteresis;
using identification::identify;

using identification::fit_quality;

TEST(BracketedSolver, FindsTheRootOfAMonotoneFunction) {
  const SolveResult r = solve_bracketed([](double t) { return t * t * t + t - 10.0; }, -5.0, 5.0);
  EXPECT_EQ(r.status, SolveStatus::kOk);
  EXPECT_NEAR(r.value * r.value * r.value + r.value, 10.0, 1e-8);
  EXPECT_LE(r.evaluations, 8 + 60);
}

TEST(BracketedSolver, ReportsNoSolutionAndNonMonotoneCharacteristics) {
  const SolveResult none = solve_bracketed([](double t) { return t + 100.0; }, -5.0, 5.0);
  EXPECT_EQ(none.status, SolveStatus::kNoSolution);
  EXPECT_DOUBLE_EQ(none.value, -5.0);  // the end nearest to a solution
  // D(T) = T^2 - 4 has two solutions on [-5, 5]: not unique, and said so.
  const SolveResult twice = solve_bracketed([](double t) { return t * t - 4.0; }, -5.0, 5.0);
  EXPECT_EQ(twice.status, SolveStatus::kNotMonotone);
  EXPECT_NEAR(std::abs(twice.value), 2.0, 1e-8);
}

TEST(BracketedSolver, IterationLimitIsReported) {
  SolverOptions opt;
  opt.max_iterations = 1;
  opt.tolerance = 1e-15;
  const SolveResult r = solve_bracketed([](double t) { return std::exp(t) - 2.0; }, -3.0, 3.0, opt);
  EXPECT_EQ(r.status, SolveStatus::kNotConverged);
}

// A stack under a large, varying compressive load whose coupling, permittivity and loop size
// change with stress (the plant's stress effects), 1 kHz, 60 s.
struct Recorded {
  std::vector<double> e, d, s, t;
};

// With creep_and_holds, the plant's creep on and the field held for 3 s of every 8 (the load keeps
// moving): the polarization and the strain creep during the holds, which plays cannot follow.
Recorded stressed_stack(bool creep_and_holds = false) {
  plant::PlantConfig config = test::stressed_stack(1000.0, 7e-6);
  config.creep.enabled = creep_and_holds;
  plant::Plant p(config);
  Recorded r;
  double e = 1e6;
  for (int k = 0; k < 60000; ++k) {
    const double time = k * 1e-3;
    if (!creep_and_holds || std::fmod(time, 8.0) < 5.0) {
      e = 1e6 + 0.9e6 * std::sin(2 * std::numbers::pi * 1.1 * time) *
                    std::cos(2 * std::numbers::pi * 0.07 * time);
    }
    const double f = 700.0 * std::sin(2 * std::numbers::pi * 0.37 * time);
    const plant::StepOutput out = p.step({e, f, 25.0});
    r.e.push_back(out.e_meas_v_per_m);
    r.d.push_back(out.d_meas_c_per_m2);
    r.s.push_back(out.s);
    r.t.push_back(out.t_pa);
  }
  return r;
}

TEST(StressHysteresis, ReconstructsStressWhereTheAffineModelCannot) {
  const Recorded r = stressed_stack();
  constexpr std::size_t kSplit = 40000;
  const auto head = [](const std::vector<double>& v) { return std::span(v).first(kSplit); };
  // 24 plays: what `identify` chooses on these 40 s (the choice itself is tested in
  // tests/identification/stress_optimum_test.cpp; here it would cost minutes under the
  // sanitizers).
  const StressHysteresisModel model =
      fit_stress_hysteresis(head(r.e), head(r.t), head(r.d), head(r.s), 1e-3, 24);
  const TransducerModel affine =
      identify({head(r.e), head(r.d), head(r.t), head(r.s), 1e-3}, Structure::kHysteresis,
               defaults_for(Structure::kHysteresis));
  StressHysteresisReconstructor vectorial(model);
  Reconstructor scalar(affine);
  std::vector<double> t_vec;
  std::vector<double> t_aff;
  std::vector<double> s_vec;
  for (std::size_t k = 0; k < r.e.size(); ++k) {
    const auto v = vectorial.step(r.e[k], r.d[k]);
    const auto a = scalar.step(r.e[k], r.d[k]);
    if (k >= kSplit) {
      t_vec.push_back(v.stress);
      t_aff.push_back(a.stress);
      s_vec.push_back(v.strain);
    }
  }
  const auto held = [](const std::vector<double>& v) { return std::span(v).subspan(kSplit); };
  const auto q_vec = fit_quality(held(r.t), t_vec);
  const auto q_aff = fit_quality(held(r.t), t_aff);
  const auto q_s = fit_quality(held(r.s), s_vec);
  std::printf("held out: T_hat %.3f %% (affine model %.2f %%), S_hat %.3f %%\n", 100 * q_vec.nrmse,
              100 * q_aff.nrmse, 100 * q_s.nrmse);
  // Measured: T_hat 0.711 % (affine model 9.01 %), S_hat 0.388 % of range, held out (0.735 and
  // 0.395 % with a free loop change); the bounds are about 1.25x, the affine model's 1.3x
  // (docs/results.md).
  EXPECT_LT(q_vec.nrmse, 0.009);
  EXPECT_LT(q_vec.nrmse, 0.2 * q_aff.nrmse);
  EXPECT_LT(q_aff.nrmse, 0.117);
  EXPECT_LT(q_s.nrmse, 0.0047);
  EXPECT_EQ(vectorial.status_counts()[SampleStatus::kOk], r.e.size());
}

TEST(StressHysteresis, CreepLagsAmongTheColumnsFollowTheCreepDuringHolds) {
  const Recorded r = stressed_stack(true);
  constexpr std::size_t kSplit = 40000;
  const auto head = [](const std::vector<double>& v) { return std::span(v).first(kSplit); };
  const auto held_out = [&r](const StressHysteresisModel& m) {
    StressHysteresisReconstructor rec(m);
    std::vector<double> t_hat;
    std::vector<double> s_hat;
    for (std::size_t k = 0; k < r.e.size(); ++k) {
      const auto est = rec.step(r.e[k], r.d[k]);
      if (k < kSplit) continue;
      t_hat.push_back(est.stress);
      s_hat.push_back(est.strain);
    }
    return std::pair{fit_quality(std::span(r.t).subspan(kSplit), t_hat).nrmse,
                     fit_quality(std::span(r.s).subspan(kSplit), s_hat).nrmse};
  };
  const auto [t_plain, s_plain] =
      held_out(fit_stress_hysteresis(head(r.e), head(r.t), head(r.d), head(r.s), 1e-3, 24));
  // Six lags on the play of threshold 0, as hysteresis-creep's defaults (creep plays made it
  // worse here: T_hat 1.87 %, S_hat 1.08 % with two).
  const StressHysteresisModel creeping =
      fit_stress_hysteresis(head(r.e), head(r.t), head(r.d), head(r.s), 1e-3, 24, {6, 0, 0.0, 0.0});
  EXPECT_EQ(creeping.basis.creep(), 6U);
  const auto [t_creep, s_creep] = held_out(creeping);
  std::printf("held out: T_hat %.3f %% -> %.3f %%, S_hat %.3f %% -> %.3f %% with creep lags\n",
              100 * t_plain, 100 * t_creep, 100 * s_plain, 100 * s_creep);
  // Measured: T_hat 1.412 -> 1.367 %, S_hat 0.720 -> 0.700 % (with a free loop change 1.479 ->
  // 1.410 %, 0.768 -> 0.735 %): the lags follow the creep of
  // the field's response; the plant's creep also follows the stress's response, which no lag of
  // the field can (docs/identification.md). Deterministic, so the small gain is asserted as a
  // gain, and each figure within 1.1x.
  EXPECT_LT(t_creep, t_plain);
  EXPECT_LT(s_creep, s_plain);
  EXPECT_LT(t_creep, 1.1 * 0.01367);
  EXPECT_LT(s_creep, 1.1 * 0.00700);
}

// A model whose sensor side is D = a + b T + c T^2 with a = E (one linear play, weight 1) and
// b, c given: the closed-form reconstruction against the exact answer.
StressHysteresisModel quadratic_model(double b, double c, double lo, double hi) {
  StressHysteresisModel m;
  m.sample_time = 1e-3;
  m.basis.thresholds = {0.0};
  m.history = {0.0};
  m.sensor = StressHysteresisSide{{1.0}, {0.0}, b, c, 0.0};
  m.stress_min = lo;
  m.stress_max = hi;
  return m;
}

TEST(StressHysteresis, ClosedFormReconstructionIsExactOnTheMonotoneBranch) {
  // D = E + 2 T + 0.01 T^2 on [-50, 50]: dD/dT = 2 + 0.02 T > 0 there (vertex at -100).
  StressHysteresisReconstructor rec(quadratic_model(2.0, 0.01, -50.0, 50.0));
  for (const double t : {-60.0, -49.0, -3.5, 0.0, 1e-9, 17.25, 49.9, 80.0}) {
    const double e = 0.3;
    const double d = e + 2.0 * t + 0.01 * t * t;
    const auto est = rec.step(e, d);
    EXPECT_EQ(est.status, SampleStatus::kOk) << t;
    EXPECT_NEAR(est.stress, t, 1e-12 * std::max(1.0, std::abs(t))) << t;
  }
  // Decreasing branch: D = E - 3 T - 0.02 T^2 on [0, 40], vertex at -75.
  StressHysteresisReconstructor down(quadratic_model(-3.0, -0.02, 0.0, 40.0));
  for (const double t : {0.0, 12.0, 39.0}) {
    const auto est = down.step(0.0, -3.0 * t - 0.02 * t * t);
    EXPECT_EQ(est.status, SampleStatus::kOk);
    EXPECT_NEAR(est.stress, t, 1e-12 * std::max(1.0, t));
  }
  // c = 0: affine.
  StressHysteresisReconstructor affine(quadratic_model(4.0, 0.0, -10.0, 10.0));
  EXPECT_NEAR(affine.step(1.0, 1.0 + 4.0 * 2.5).stress, 2.5, 1e-15);
}

TEST(StressHysteresis, ClosedFormReportsNonMonotoneAndMissingSolutions) {
  // Vertex at T = 0 inside [-10, 10]: D = T^2 is not invertible there.
  StressHysteresisReconstructor rec(quadratic_model(0.0, 1.0, -10.0, 10.0));
  EXPECT_EQ(rec.step(0.0, 4.0).status, SampleStatus::kNotMonotone);
  // D = T^2 + 2 T (vertex -1) on [0, 10]: monotone, but D = -5 is below the minimum -1.
  StressHysteresisReconstructor none(quadratic_model(2.0, 1.0, 0.0, 10.0));
  const auto est = none.step(0.0, -5.0);
  EXPECT_EQ(est.status, SampleStatus::kNoSolution);
  EXPECT_DOUBLE_EQ(est.stress, -1.0);  // the vertex: the stress closest to reproducing D
  EXPECT_EQ(none.status_counts()[SampleStatus::kNoSolution], 1U);
}

TEST(StressHysteresis, StateSaveAndRestoreReplaysExactly) {
  const Recorded r = stressed_stack();
  StressHysteresisReconstructor rec(
      fit_stress_hysteresis(std::span(r.e).first(20000), std::span(r.t).first(20000),
                            std::span(r.d).first(20000), std::span(r.s).first(20000), 1e-3, 8));
  for (std::size_t k = 0; k < 1000; ++k)
    rec.step(r.e[k], r.d[k]);
  std::vector<double> saved(rec.state_size());
  rec.save_state(saved);
  std::vector<double> first;
  for (std::size_t k = 1000; k < 2000; ++k)
    first.push_back(rec.step(r.e[k], r.d[k]).stress);
  rec.restore_state(saved);
  for (std::size_t k = 1000; k < 2000; ++k)
    ASSERT_EQ(rec.step(r.e[k], r.d[k]).stress, first[k - 1000]);
}

}  // namespace
}  // namespace selfsense::models
