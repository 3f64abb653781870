// Loop size that changes with stress (issue 7, third stack): recordings made by the
// stress-dependent class itself on another play grid (support/operator_recordings.hpp), the
// plain unconstrained least-squares fit of the library's basis started from the generator's
// history as the reference, and `identify --structure stress-hysteresis` measured against it
// on a second recording with new excitation.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cstdio>
#include <string>
#include <vector>

#include "selfsense/identification/fit_quality.hpp"
#include "selfsense/identification/transducer_fit.hpp"
#include "selfsense/models/stress_hysteresis.hpp"
#include "support/operator_recordings.hpp"

namespace selfsense::identification {
namespace {

constexpr double kTs = 1e-3;
constexpr std::size_t kFitSamples = 60000;
constexpr std::size_t kValidationSamples = 40000;
constexpr double kNoise = 5e-4;

const test::RecordingPair& recordings() {
  static const test::RecordingPair r = [] {
    const models::StressHysteresisModel truth = test::stress_generator(kTs, 0.3);
    return test::record_pair([&truth] { return models::StressHysteresisForward(truth); },
                             kFitSamples, kValidationSamples, kTs, kNoise);
  }();
  return r;
}

struct Figures {
  double t_hat{0.0}, s_hat{0.0};
  std::size_t unsolved{0};
};

Figures reconstruct(const models::StressHysteresisModel& m, const test::OperatorRecording& r) {
  models::StressHysteresisReconstructor rec(m);
  std::vector<double> t_hat;
  std::vector<double> s_hat;
  Figures f;
  for (std::size_t k = 0; k < r.e.size(); ++k) {
    const auto est = rec.step(r.e[k], r.d[k]);
    t_hat.push_back(est.stress);
    s_hat.push_back(est.strain);
    if (est.status != models::SampleStatus::kOk) ++f.unsolved;
  }
  f.t_hat = fit_quality(r.t, t_hat).nrmse;
  f.s_hat = fit_quality(r.s, s_hat).nrmse;
  return f;
}

Figures reconstruct(const models::TransducerModel& m, const test::OperatorRecording& r) {
  models::Reconstructor rec(m);
  std::vector<double> t_hat;
  std::vector<double> s_hat;
  for (std::size_t k = 0; k < r.e.size(); ++k) {
    const auto est = rec.step(r.e[k], r.d[k]);
    t_hat.push_back(est.stress);
    s_hat.push_back(est.strain);
  }
  return {fit_quality(r.t, t_hat).nrmse, fit_quality(r.s, s_hat).nrmse, 0};
}

// Unconstrained least squares (column-scaled QR) of the library's columns q, T q, T, T^2, 1,
// the plays started from the generator's history.
models::StressHysteresisModel reference_fit(const models::StressHysteresisModel& layout,
                                            const test::OperatorRecording& r) {
  models::StressHysteresisModel ref = layout;
  ref.history = {0.0, test::kFieldMax, test::kFieldMin, 0.0};
  operators::RegressorStream stream(ref.basis, ref.history);
  const std::size_t p = ref.basis.columns();
  const auto cols = static_cast<Eigen::Index>(2 * p + 3);
  Eigen::MatrixXd a(static_cast<Eigen::Index>(r.e.size()), cols);
  for (std::size_t k = 0; k < r.e.size(); ++k) {
    const auto q = stream.next(r.e[k]);
    const auto row = static_cast<Eigen::Index>(k);
    for (std::size_t i = 0; i < p; ++i) {
      a(row, static_cast<Eigen::Index>(i)) = q[i];
      a(row, static_cast<Eigen::Index>(p + i)) = r.t[k] * q[i];
    }
    a(row, cols - 3) = r.t[k];
    a(row, cols - 2) = r.t[k] * r.t[k];
    a(row, cols - 1) = 1.0;
  }
  const Eigen::VectorXd scale = a.colwise().norm().cwiseInverse().transpose();
  const auto qr = (a * scale.asDiagonal()).colPivHouseholderQr();
  const auto solve = [&](const std::vector<double>& y) {
    const Eigen::VectorXd theta =
        scale.asDiagonal() * qr.solve(Eigen::Map<const Eigen::VectorXd>(y.data(), a.rows()));
    models::StressHysteresisSide side;
    side.base.assign(theta.data(), theta.data() + p);
    side.stress.assign(theta.data() + p, theta.data() + 2 * p);
    side.linear = theta(cols - 3);
    side.quadratic = theta(cols - 2);
    side.offset = theta(cols - 1);
    return side;
  };
  ref.sensor = solve(r.d);
  ref.actuator = solve(r.s);
  return ref;
}

void print(const char* what, const Figures& f) {
  std::printf("%-44s T_hat %.4f  S_hat %.4f %%  unsolved %zu\n", what, 100 * f.t_hat, 100 * f.s_hat,
              f.unsolved);
}

// With the sizes given and a free loop change (the reference's columns): the fit reaches the
// least-squares optimum of its basis on the fitting recording and on the new one, and more
// plays never fit worse. Before the remanent-state
// search (the plays started demagnetised at the first sample) 48 plays were 13x off on the
// fit and 23x on new data; with the start of the affine-in-T search alone, 1.4x and 3x (the
// turning point 0.7 % of the field range off).
TEST(StressHysteresisOptimum, ReachesTheLeastSquaresOptimumOfEachBasis) {
  const test::RecordingPair& r = recordings();
  const TransducerSignals fit{r.fit.e, r.fit.d, r.fit.t, r.fit.s, kTs};
  Figures previous{1.0, 1.0, 0};
  for (const std::size_t plays : kStressPlayCandidates) {
    IdentificationOptions o = defaults_for(models::Structure::kStressHysteresis);
    o.plays = plays;
    o.choose_plays = false;
    o.loop_change = LoopChange::kFree;
    const models::TransducerModel lib = identify(fit, models::Structure::kStressHysteresis, o);
    const models::StressHysteresisModel ref = reference_fit(*lib.vectorial, r.fit);
    const std::string label = std::to_string(plays) + " plays, ";
    const Figures ls_fit = reconstruct(ref, r.fit);
    const Figures ls_val = reconstruct(ref, r.validation);
    const Figures lib_fit = reconstruct(*lib.vectorial, r.fit);
    const Figures lib_val = reconstruct(*lib.vectorial, r.validation);
    print((label + "least squares, fit").c_str(), ls_fit);
    print((label + "least squares, validation").c_str(), ls_val);
    print((label + "identify, fit").c_str(), lib_fit);
    print((label + "identify, validation").c_str(), lib_val);
    // Measured: within 0.5 % of least squares on both (1.00x).
    EXPECT_LE(lib_fit.t_hat, 1.05 * ls_fit.t_hat) << label;
    EXPECT_LE(lib_fit.s_hat, 1.05 * ls_fit.s_hat) << label;
    EXPECT_LE(lib_val.t_hat, 1.1 * ls_val.t_hat) << label;
    EXPECT_LE(lib_val.s_hat, 1.1 * ls_val.s_hat) << label;
    EXPECT_EQ(lib_val.unsolved, 0U) << label;
    EXPECT_LE(lib_fit.t_hat, previous.t_hat * (1.0 + 1e-3)) << label;
    EXPECT_LE(lib_fit.s_hat, previous.s_hat * (1.0 + 1e-3)) << label;
    previous = lib_fit;
  }
}

// With the default options the play count is chosen on the fitting recording alone (48 here),
// and the new recording is reconstructed at the noise floor, where the affine-in-T
// hysteresis-creep model cannot follow the loop size (measured 0.111 / 0.083 % against
// 4.97 / 3.31 %; the latter bounded at about 1.3x too).
TEST(StressHysteresisOptimum, ChosenSizeReachesTheNoiseFloorOnANewRecording) {
  const test::RecordingPair& r = recordings();
  const TransducerSignals fit{r.fit.e, r.fit.d, r.fit.t, r.fit.s, kTs};
  const models::TransducerModel lib = identify(fit, models::Structure::kStressHysteresis,
                                               defaults_for(models::Structure::kStressHysteresis));
  const models::TransducerModel affine = identify(
      fit, models::Structure::kHysteresisCreep, defaults_for(models::Structure::kHysteresisCreep));
  const Figures val = reconstruct(*lib.vectorial, r.validation);
  const Figures affine_val = reconstruct(affine, r.validation);
  std::printf("chosen: %zu plays\n", lib.vectorial->basis.thresholds.size() - 1);
  print("identify (chosen), validation", val);
  print("hysteresis-creep (affine in T), validation", affine_val);
  EXPECT_EQ(lib.vectorial->basis.thresholds.size(), 49U);
  // 0.05 % noise on T and S.
  EXPECT_LE(val.t_hat, 2.8 * kNoise);
  EXPECT_LE(val.s_hat, 2.1 * kNoise);
  EXPECT_EQ(val.unsolved, 0U);
  EXPECT_GE(affine_val.t_hat, 20.0 * val.t_hat);
  EXPECT_GE(affine_val.s_hat, 20.0 * val.s_hat);
  EXPECT_LE(affine_val.t_hat, 0.065);
  EXPECT_LE(affine_val.s_hat, 0.043);
}

// The generator's loop scales with T (W1 a multiple of W0 on its own grid), which the shaped
// loop change (the default: W1_i = W0_i times a quadratic in the threshold, five parameters per
// side instead of 49) holds on the library's grid: the new recording at the free fit's floor
// (measured: T_hat 0.1110 against 0.1113 %, S_hat 0.0834 against 0.0834 %), and every W1_i /
// W0_i past the field's own play on one quadratic in the threshold, where the free fit's are
// not (the worst misfit in units of the mean ratio: measured 0.0065, the last alternation's W0
// against its reference, and 0.16).
TEST(StressHysteresisOptimum, ShapedLoopChangeHoldsTheFreeFloorWhereTheLoopScales) {
  const test::RecordingPair& r = recordings();
  const TransducerSignals fit{r.fit.e, r.fit.d, r.fit.t, r.fit.s, kTs};
  IdentificationOptions options = defaults_for(models::Structure::kStressHysteresis);
  options.choose_plays = false;
  options.plays = 48;
  const models::TransducerModel shaped =
      identify(fit, models::Structure::kStressHysteresis, options);
  options.loop_change = LoopChange::kFree;
  const models::TransducerModel free = identify(fit, models::Structure::kStressHysteresis, options);
  const Figures shaped_val = reconstruct(*shaped.vectorial, r.validation);
  const Figures free_val = reconstruct(*free.vectorial, r.validation);
  print("shaped loop change, validation", shaped_val);
  print("free loop change, validation", free_val);
  EXPECT_LE(shaped_val.t_hat, 1.05 * free_val.t_hat);
  EXPECT_LE(shaped_val.s_hat, 1.05 * free_val.s_hat);
  EXPECT_EQ(shaped_val.unsolved, 0U);
  // The ratios' worst misfit by a quadratic in the threshold, relative to their spread.
  const auto off_quadratic = [](const models::StressHysteresisModel& m) {
    const std::vector<double>& th = m.basis.thresholds;
    const auto n = static_cast<Eigen::Index>(th.size() - 1);
    Eigen::MatrixXd a(n, 3);
    Eigen::VectorXd ratio(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      const auto k = static_cast<std::size_t>(i + 1);
      a(i, 0) = 1.0;
      a(i, 1) = th[k];
      a(i, 2) = th[k] * th[k];
      ratio(i) = m.sensor->stress[k] / m.sensor->base[k];
    }
    const Eigen::VectorXd scale = a.colwise().norm().cwiseInverse().transpose();
    const Eigen::VectorXd c =
        scale.asDiagonal() * (a * scale.asDiagonal()).colPivHouseholderQr().solve(ratio);
    return (a * c - ratio).cwiseAbs().maxCoeff() / ratio.cwiseAbs().mean();
  };
  std::printf("W1 / W0 off a quadratic in the threshold: shaped %.2g, free %.2g\n",
              off_quadratic(*shaped.vectorial), off_quadratic(*free.vectorial));
  EXPECT_LE(off_quadratic(*shaped.vectorial), 0.02);
  EXPECT_GE(off_quadratic(*free.vectorial), 0.08);
}

// At most a third of the samples as rows of each fit (IdentificationOptions::max_rows: every 3rd,
// the diagnosis's re-identifications of long records): the same size chosen and the same floor
// on the new recording, within a tenth of the fit on every row.
TEST(StressHysteresisOptimum, EveryThirdRowReachesTheSameFloor) {
  const test::RecordingPair& r = recordings();
  const TransducerSignals fit{r.fit.e, r.fit.d, r.fit.t, r.fit.s, kTs};
  IdentificationOptions options = defaults_for(models::Structure::kStressHysteresis);
  const models::TransducerModel every =
      identify(fit, models::Structure::kStressHysteresis, options);
  options.max_rows = kFitSamples / 3;
  const models::TransducerModel third =
      identify(fit, models::Structure::kStressHysteresis, options);
  const Figures every_val = reconstruct(*every.vectorial, r.validation);
  const Figures third_val = reconstruct(*third.vectorial, r.validation);
  print("every row, validation", every_val);
  print("every third row, validation", third_val);
  EXPECT_NE(third.vectorial->sensor->base, every.vectorial->sensor->base);  // other rows
  EXPECT_EQ(third.vectorial->basis.thresholds.size(), 49U);
  EXPECT_LE(third_val.t_hat, 1.1 * every_val.t_hat);
  EXPECT_LE(third_val.s_hat, 1.1 * every_val.s_hat);
  EXPECT_EQ(third_val.unsolved, 0U);
}

}  // namespace
}  // namespace selfsense::identification
