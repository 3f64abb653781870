// Identification against the optimum of its own model class (issue 7): recordings made by the
// operators themselves (support/operator_recordings.hpp), the plain unconstrained least-squares
// fit of the same basis as the reference, and the library's identify() measured on the fitting
// recording and on a second recording with new excitation.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cstdio>
#include <string>
#include <vector>

#include "selfsense/identification/fit_quality.hpp"
#include "selfsense/identification/regressors.hpp"
#include "selfsense/identification/transducer_fit.hpp"
#include "selfsense/models/reconstructor.hpp"
#include "selfsense/operators/linear_creep.hpp"
#include "support/operator_recordings.hpp"

namespace selfsense::identification {
namespace {

constexpr double kTs = 1e-3;
constexpr std::size_t kFitSamples = 60000;
constexpr std::size_t kValidationSamples = 40000;
constexpr double kNoise = 5e-4;  // 0.05 % of range on S and T

using Recordings = test::RecordingPair;

Recordings recordings(bool creep, double asymmetry) {
  const models::TransducerModel truth = test::generator_transducer(kTs, creep, asymmetry);
  return test::record_pair([&truth] { return models::ForwardModel(truth); }, kFitSamples,
                           kValidationSamples, kTs, kNoise);
}

// nrmse (fraction of range) of the forward model (D, S from E and the measured T) and of the
// reconstruction (T_hat, S_hat from E and D).
struct Figures {
  double d{0.0}, s{0.0}, t_hat{0.0}, s_hat{0.0};
};

struct Series {
  std::vector<double> d, s, t_hat, s_hat;
};

Figures figures(const test::OperatorRecording& r, const Series& m, std::size_t from) {
  const auto q = [from](const std::vector<double>& rec, const std::vector<double>& model) {
    return fit_quality(std::span(rec).subspan(from), std::span(model).subspan(from)).nrmse;
  };
  return {q(r.d, m.d), q(r.s, m.s), q(r.t, m.t_hat), q(r.s, m.s_hat)};
}

Series run_model(const models::TransducerModel& model, const test::OperatorRecording& r) {
  Series out;
  models::ForwardModel forward(model);
  models::Reconstructor rec(model);
  for (std::size_t k = 0; k < r.e.size(); ++k) {
    const auto y = forward.step(r.e[k], r.t[k]);
    out.d.push_back(y.sensed);
    out.s.push_back(y.strain);
    const auto est = rec.step(r.e[k], r.d[k]);
    out.t_hat.push_back(est.stress);
    out.s_hat.push_back(est.strain);
  }
  return out;
}

// The basis fit_operator builds for these sizes (its threshold and eigenvalue grids).
OperatorBasis basis_of(std::size_t plays, std::size_t eigenvalues, std::size_t creep_plays,
                       double x_range, double duration) {
  OperatorBasis b;
  b.thresholds.push_back(0.0);
  for (std::size_t i = 1; i <= plays; ++i)
    b.thresholds.push_back(0.5 * x_range * static_cast<double>(i) / static_cast<double>(plays + 1));
  if (eigenvalues > 0) {
    b.eigenvalues = operators::log_spaced_eigenvalues(100.0, 3.0 / duration, eigenvalues);
    for (const double l : b.eigenvalues)
      b.gains.push_back(-std::expm1(-l * kTs));
    b.creep_rows.push_back(0);
    for (std::size_t k = 1; k <= creep_plays; ++k)
      b.creep_rows.push_back(k * (plays + 1) / (creep_plays + 1));
  }
  return b;
}

// Plain unconstrained least squares (column-scaled QR) of y = Phi theta + g T + offset over
// samples [0, fit_to), the operator started from the generator's own history.
struct Reference {
  OperatorBasis basis;
  Eigen::VectorXd sensor, actuator;  // operator weights, then g, offset
};

Eigen::MatrixXd regressors(const OperatorBasis& basis, const test::OperatorRecording& r,
                           std::size_t to) {
  const std::vector<double> history{0.0, test::kFieldMax, test::kFieldMin, 0.0};
  RegressorStream stream(basis, history);
  const auto ops = static_cast<Eigen::Index>(basis.columns());
  Eigen::MatrixXd a(static_cast<Eigen::Index>(to), ops + 2);
  for (std::size_t k = 0; k < to; ++k) {
    const auto phi = stream.next(r.e[k]);
    const auto row = static_cast<Eigen::Index>(k);
    for (Eigen::Index c = 0; c < ops; ++c)
      a(row, c) = phi[static_cast<std::size_t>(c)];
    a(row, ops) = r.t[k];
    a(row, ops + 1) = 1.0;
  }
  return a;
}

Eigen::VectorXd least_squares(const Eigen::MatrixXd& a, std::span<const double> y) {
  const Eigen::VectorXd scale = a.colwise().norm().cwiseInverse().transpose();
  const Eigen::MatrixXd scaled = a * scale.asDiagonal();
  const Eigen::VectorXd target = Eigen::Map<const Eigen::VectorXd>(y.data(), a.rows());
  return scale.asDiagonal() * scaled.colPivHouseholderQr().solve(target);
}

Reference reference_fit(const test::OperatorRecording& r, std::size_t plays,
                        std::size_t eigenvalues, std::size_t creep_plays, std::size_t fit_to) {
  Reference ref;
  const auto [lo, hi] =
      std::minmax_element(r.e.begin(), r.e.begin() + static_cast<std::ptrdiff_t>(fit_to));
  ref.basis =
      basis_of(plays, eigenvalues, creep_plays, *hi - *lo, kTs * static_cast<double>(fit_to));
  const Eigen::MatrixXd a = regressors(ref.basis, r, fit_to);
  ref.sensor = least_squares(a, std::span(r.d).first(fit_to));
  ref.actuator = least_squares(a, std::span(r.s).first(fit_to));
  return ref;
}

Series run_reference(const Reference& ref, const test::OperatorRecording& r) {
  const Eigen::MatrixXd a = regressors(ref.basis, r, r.e.size());
  const Eigen::Index ops = a.cols() - 2;
  Series out;
  const Eigen::VectorXd d = a * ref.sensor;
  const Eigen::VectorXd s = a * ref.actuator;
  const Eigen::VectorXd d_unloaded = a.leftCols(ops) * ref.sensor.head(ops);
  const Eigen::VectorXd s_unloaded = a.leftCols(ops) * ref.actuator.head(ops);
  for (Eigen::Index k = 0; k < a.rows(); ++k) {
    out.d.push_back(d(k));
    out.s.push_back(s(k));
    const double t_hat =
        (r.d[static_cast<std::size_t>(k)] - d_unloaded(k) - ref.sensor(ops + 1)) / ref.sensor(ops);
    out.t_hat.push_back(t_hat);
    out.s_hat.push_back(s_unloaded(k) + ref.actuator(ops) * t_hat + ref.actuator(ops + 1));
  }
  return out;
}

models::TransducerModel library_fit(const test::OperatorRecording& r, std::size_t plays,
                                    std::size_t dead_zones, std::size_t eigenvalues,
                                    std::size_t creep_plays, std::size_t fit_to,
                                    std::size_t bias_levels = 0) {
  identification::IdentificationOptions o;
  o.bias_levels = bias_levels;
  o.plays = plays;
  o.dead_zones = dead_zones;
  o.eigenvalues = eigenvalues;
  o.creep_plays = creep_plays;
  const identification::TransducerSignals s{
      std::span(r.e).first(fit_to), std::span(r.d).first(fit_to), std::span(r.t).first(fit_to),
      std::span(r.s).first(fit_to), kTs};
  return identification::identify(
      s, eigenvalues > 0 ? models::Structure::kHysteresisCreep : models::Structure::kHysteresis, o);
}

void print(const char* what, const Figures& f) {
  std::printf("%-36s D %.4f  S %.4f  T_hat %.4f  S_hat %.4f %%\n", what, 100 * f.d, 100 * f.s,
              100 * f.t_hat, 100 * f.s_hat);
}

// Recordings are made once per generator.
const Recordings& cached(bool creep, double asymmetry) {
  static const Recordings pi_creep = recordings(true, 0.0);
  static const Recordings pi_only = recordings(false, 0.0);
  static const Recordings mild = recordings(true, 0.2);
  static const Recordings strong = recordings(true, 1.0);
  if (asymmetry == 0.0) return creep ? pi_creep : pi_only;
  return asymmetry < 0.5 ? mild : strong;
}

// The default sizes of hysteresis-creep (24 plays, 8 dead zones, 6 x 3 creep elements).
constexpr std::size_t kPlays = 24;
constexpr std::size_t kDeadZones = 8;
constexpr std::size_t kEigenvalues = 6;
constexpr std::size_t kCreepPlays = 2;

// Generator inside the model class up to the grids (PI on other thresholds, affine T, creep
// with other eigenvalues): the library's fit is the least-squares optimum of its basis, on
// the fitting recording and on a new one. The reference's basis has no dead zones (their
// superposition wraps the operator's output, which no linear least squares can fit), so the
// library fits the same basis here: the plays and creep elements of the default sizes, no dead
// zones (the generator is symmetric; DeadZonesAbsorbTheAsymmetry and
// RicherBasesNeverFitTheFittingDataWorse cover them). Before the fix of the remanent-state
// search (scored without creep) it was 1.9x off on T_hat and 2.4x on D.
TEST(IdentificationOptimum, ReachesTheLeastSquaresOptimumOnANewRecording) {
  for (const bool creep : {false, true}) {
    const Recordings& r = cached(creep, 0.0);
    const std::size_t eig = creep ? kEigenvalues : 0;
    const std::size_t cp = creep ? kCreepPlays : 0;
    const Reference ref = reference_fit(r.fit, kPlays, eig, cp, kFitSamples);
    const models::TransducerModel m = library_fit(r.fit, kPlays, 0, eig, cp, kFitSamples);
    const Figures ls_fit = figures(r.fit, run_reference(ref, r.fit), 0);
    const Figures ls_val = figures(r.validation, run_reference(ref, r.validation), 0);
    const Figures lib_fit = figures(r.fit, run_model(m, r.fit), 0);
    const Figures lib_val = figures(r.validation, run_model(m, r.validation), 0);
    print(creep ? "creep, least squares, fit" : "least squares, fit", ls_fit);
    print(creep ? "creep, least squares, validation" : "least squares, validation", ls_val);
    print(creep ? "creep, identify, fit" : "identify, fit", lib_fit);
    print(creep ? "creep, identify, validation" : "identify, validation", lib_val);
    // Measured: without creep identify gives least squares' figures (to 4 digits); with creep
    // within 2.2 % of it on the fit (D), 0.92x of it on the validation recording (least
    // squares has no bounds and overfits a little).
    EXPECT_LE(lib_fit.d, 1.05 * ls_fit.d);
    EXPECT_LE(lib_fit.s, 1.05 * ls_fit.s);
    EXPECT_LE(lib_val.t_hat, 1.25 * ls_val.t_hat);
    EXPECT_LE(lib_val.s_hat, 1.25 * ls_val.s_hat);
    // S and T carry 0.05 % noise: S_hat is within 4x of that floor, T_hat within 25x (the
    // reconstruction divides the D error by the small coupling).
    EXPECT_LE(lib_val.s_hat, 4.0 * kNoise);
    EXPECT_LE(lib_val.t_hat, 25.0 * kNoise);
  }
}

// With creep, the tail of the fitting recording that the fit did not see (the same basis as
// the reference, as above).
TEST(IdentificationOptimum, HeldOutTailWithCreepStaysAtTheOptimum) {
  const Recordings& r = cached(true, 0.0);
  const std::size_t split = kFitSamples * 3 / 4;
  const Reference ref = reference_fit(r.fit, kPlays, kEigenvalues, kCreepPlays, split);
  const models::TransducerModel m = library_fit(r.fit, kPlays, 0, kEigenvalues, kCreepPlays, split);
  const Figures ls_tail = figures(r.fit, run_reference(ref, r.fit), split);
  const Figures lib_tail = figures(r.fit, run_model(m, r.fit), split);
  print("creep, least squares, held-out tail", ls_tail);
  print("creep, identify, held-out tail", lib_tail);
  // Measured: 0.83x of least squares (was 2.0x).
  EXPECT_LE(lib_tail.t_hat, 1.2 * ls_tail.t_hat);
  EXPECT_LE(lib_tail.s_hat, 1.2 * ls_tail.s_hat);
}

// Strong asymmetry and creep: more plays, dead zones or creep terms never fit the fitting
// recording worse (before the fix, 48 plays fitted D 1.7x worse than 24 with 8 dead zones).
TEST(IdentificationOptimum, RicherBasesNeverFitTheFittingDataWorse) {
  const Recordings& r = cached(true, 1.0);
  struct Size {
    std::size_t plays, dead_zones, eigenvalues, bias_levels{0};
  };
  // Each one adds to the one before (hinge levels at k / (K + 1) of a play's span nest for
  // K = 1, 3, 7).
  const std::vector<std::vector<Size>> chains{
      {{16, 8, 6}, {24, 8, 6}, {48, 8, 6}},
      {{24, 0, 6}, {24, 4, 6}, {24, 8, 6}},
      {{24, 8, 0}, {24, 8, 6}},
      {{24, 0, 6, 0}, {24, 0, 6, 1}, {24, 0, 6, 3}},
      {{24, 8, 6, 0}, {24, 8, 6, 1}, {24, 8, 6, 3}},
  };
  for (const auto& chain : chains) {
    Figures previous{1.0, 1.0, 1.0, 1.0};
    for (const Size& size : chain) {
      const models::TransducerModel m =
          library_fit(r.fit, size.plays, size.dead_zones, size.eigenvalues,
                      size.eigenvalues > 0 ? kCreepPlays : 0, kFitSamples, size.bias_levels);
      const Figures f = figures(r.fit, run_model(m, r.fit), 0);
      const std::string label = std::to_string(size.plays) + " plays " +
                                std::to_string(size.dead_zones) + " dz " +
                                std::to_string(size.eigenvalues) + " eig " +
                                std::to_string(size.bias_levels) + " bias, fit";
      print(label.c_str(), f);
      EXPECT_LE(f.d, previous.d * (1.0 + 1e-3)) << label;
      EXPECT_LE(f.s, previous.s * (1.0 + 1e-3)) << label;
      previous = f;
    }
  }
}

// Mild asymmetry (inside the class with dead zones, up to the grids): 48 plays and 8 dead
// zones come as close to the new recording as least squares does on the symmetric generator
// (measured 1.25x on T_hat, 1.1x on S_hat; 6.8x and 4.8x before the fix).
TEST(IdentificationOptimum, DeadZonesAbsorbTheAsymmetry) {
  const Recordings& symmetric = cached(true, 0.0);
  const Recordings& r = cached(true, 0.2);
  const Reference ref = reference_fit(symmetric.fit, 48, kEigenvalues, kCreepPlays, kFitSamples);
  const Figures ls_val = figures(symmetric.validation, run_reference(ref, symmetric.validation), 0);
  const models::TransducerModel m =
      library_fit(r.fit, 48, kDeadZones, kEigenvalues, kCreepPlays, kFitSamples);
  const Figures lib_val = figures(r.validation, run_model(m, r.validation), 0);
  print("symmetric, least squares 48, validation", ls_val);
  print("asymmetric, identify 48/8, validation", lib_val);
  EXPECT_LE(lib_val.t_hat, 1.6 * ls_val.t_hat);
  EXPECT_LE(lib_val.s_hat, 1.4 * ls_val.s_hat);
}

}  // namespace
}  // namespace selfsense::identification
