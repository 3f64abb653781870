// Issue 24's proof for the sensorless slice: the main job's model (preisach-creep, identified
// on config/plant/reconstruction.yaml at 25 degC) reconstructs a recording of the same plant
// under excitation it never saw (config/plant/reconstruction-validation.yaml, other seed) while
// the stack warms 25 -> 55 degC with the coefficients of config/plant/temperature.yaml; with the
// drift estimated from E and D alone, without it, and with the recorded temperature.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "selfsense/adaptation/adapted_reconstruction.hpp"
#include "selfsense/adaptation/temperature_fit.hpp"
#include "selfsense/identification/fit_quality.hpp"
#include "selfsense/identification/transducer_fit.hpp"
#include "selfsense/models/reconstructor.hpp"
#include "selfsense/plant/plant.hpp"
#include "selfsense/plant_io/plant_yaml.hpp"

namespace selfsense {
namespace {

using identification::fit_quality;
using identification::FitQuality;

struct Recorded {
  std::vector<double> e, d, s, t, temp;
};

Recorded record(const plant::PlantConfig& config, const plant::Excitation& ex) {
  plant::Plant p(config);
  Recorded r;
  for (const plant::StepInput& in : ex.inputs()) {
    const plant::StepOutput out = p.step(in);
    r.e.push_back(out.e_meas_v_per_m);
    r.d.push_back(out.d_meas_c_per_m2);
    r.s.push_back(out.s);
    r.t.push_back(out.t_pa);
    r.temp.push_back(out.temp_degc);
  }
  return r;
}

// The main job's model: identified at 25 degC on the identification excitation, seed 1.
const models::TransducerModel& main_job_model() {
  static const models::TransducerModel model = [] {
    plant::PlantFile f =
        plant::load_plant_file(SELFSENSE_SOURCE_DIR "/config/plant/reconstruction.yaml");
    f.plant.seed = 1;
    const Recorded r = record(
        f.plant, plant::make_excitation("identification", f.excitation, f.plant.sample_rate_hz, 1));
    return identification::identify(
        {r.e, r.d, r.t, r.s, 1.0 / f.plant.sample_rate_hz}, models::Structure::kPreisachCreep,
        identification::defaults_for(models::Structure::kPreisachCreep));
  }();
  return model;
}

// A plant file of config/plant/ with config/plant/temperature.yaml's coefficients and the
// noise seed `seed`.
plant::PlantFile warming_plant(const char* name, std::uint64_t seed) {
  plant::PlantFile f =
      plant::load_plant_file(std::string(SELFSENSE_SOURCE_DIR "/config/plant/") + name);
  f.plant.temperature =
      plant::load_plant_file(SELFSENSE_SOURCE_DIR "/config/plant/temperature.yaml")
          .plant.temperature;
  f.plant.seed = seed;
  return f;
}

// The main job's model with temperature coefficients fitted on a ramp recording (issue 24 items 1
// and 5): the identification plant and excitation (config/plant/reconstruction.yaml, seed 2:
// other noise than the model's recording) with config/plant/temperature.yaml's coefficients,
// warming 25 -> 55 degC. The validation recordings' excitation (mix) is never seen.
const models::TransducerModel& model_with_coefficients() {
  static const models::TransducerModel model = [] {
    plant::PlantFile f = warming_plant("reconstruction.yaml", 2);
    plant::Excitation ex =
        plant::make_excitation("identification", f.excitation, f.plant.sample_rate_hz, 2);
    f.excitation.temperature = {25.0, 55.0};
    plant::apply_load_and_temperature(f.excitation, f.plant.sample_rate_hz, ex);
    const Recorded r = record(f.plant, ex);
    models::TransducerModel m = main_job_model();
    const adaptation::TemperatureFitResult fit =
        adaptation::fit_temperature(m, {r.e, r.d, r.t, r.s, r.temp}, 25.0);
    const models::SideTemperature& s = fit.coefficients.sensor;
    const models::SideTemperature& a = fit.coefficients.actuator;
    std::printf(
        "fitted on %zu samples (%.0f s): sensor L %+.3e %+.3e, H %+.3e %+.3e, d %+.3e %+.3e; "
        "actuator L %+.3e %+.3e, H %+.3e %+.3e, s %+.3e %+.3e; residual RMS sensor %.3g -> "
        "%.3g C/m^2, actuator %.3g -> %.3g; on %zu increments L %+.3e, H %+.3e\n",
        fit.samples, static_cast<double>(r.e.size()) / f.plant.sample_rate_hz, s.linear.per_k,
        s.linear.per_k2, s.loop.per_k, s.loop.per_k2, s.coupling.per_k, s.coupling.per_k2,
        a.linear.per_k, a.linear.per_k2, a.loop.per_k, a.loop.per_k2, a.coupling.per_k,
        a.coupling.per_k2, fit.sensor_rms_before, fit.sensor_rms_after, fit.actuator_rms_before,
        fit.actuator_rms_after, fit.increments, fit.coefficients.increments.linear_per_k,
        fit.coefficients.increments.loop_per_k);
    m.temperature = fit.coefficients;
    return m;
  }();
  return model;
}

// The validation plant with config/plant/temperature.yaml's coefficients, the mix excitation
// repeated `repeats` times, the temperature ramping start -> end over the whole recording (or
// swinging, below).
Recorded warming_recording(std::uint64_t seed, double start_degc, double end_degc, int repeats,
                           bool swings = false) {
  plant::PlantFile f = warming_plant("reconstruction-validation.yaml", seed);
  plant::Excitation one = plant::make_excitation("mix", f.excitation, f.plant.sample_rate_hz, seed);
  plant::Excitation ex = one;
  for (int i = 1; i < repeats; ++i) {
    ex.e_v_per_m.insert(ex.e_v_per_m.end(), one.e_v_per_m.begin(), one.e_v_per_m.end());
  }
  f.excitation.temperature = {start_degc, end_degc};
  plant::apply_load_and_temperature(f.excitation, f.plant.sample_rate_hz, ex);
  if (swings) {
    // Slow random swings: up from 25 to 40 degC over 30 s, then three slow sines of random
    // phase (periods 150, 67 and 41 s; 6, 5 and 3 K) about 40 degC.
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> phase(0.0, 2.0 * std::numbers::pi);
    const double p1 = phase(rng);
    const double p2 = phase(rng);
    const double p3 = phase(rng);
    const double w = 2.0 * std::numbers::pi;
    for (std::size_t k = 0; k < ex.size(); ++k) {
      const double t = static_cast<double>(k) / f.plant.sample_rate_hz;
      const double rise = std::min(1.0, t / 30.0);
      const double swing = 6.0 * std::sin(w * t / 150.0 + p1) + 5.0 * std::sin(w * t / 67.0 + p2) +
                           3.0 * std::sin(w * t / 41.0 + p3);
      ex.temp_degc[k] = 25.0 + rise * (15.0 + swing);
    }
  }
  return record(f.plant, ex);
}

struct Figures {
  FitQuality strain, stress;
  double temperature_rms_k{0.0};
  double temperature_max_k{0.0};
};

// kind: 0 the model as identified, 1 adapted from E and D, 2 the recorded temperature, 3 the
// recorded temperature with the fitted coefficients (model_with_coefficients), 4 adapted from E
// and D with the fitted coefficients.
Figures reconstruct(const Recorded& r, int kind, std::size_t settle) {
  const models::TransducerModel& model = kind >= 3 ? model_with_coefficients() : main_job_model();
  std::vector<double> s_hat(r.e.size());
  std::vector<double> t_hat(r.e.size());
  double sq = 0.0;
  double worst = 0.0;
  if (kind == 0) {
    models::Reconstructor rec(model);
    for (std::size_t k = 0; k < r.e.size(); ++k) {
      const auto est = rec.step(r.e[k], r.d[k]);
      s_hat[k] = est.strain;
      t_hat[k] = est.stress;
    }
  } else {
    adaptation::DriftEstimatorConfig config{};
    config.frozen = kind == 2 || kind == 3;
    adaptation::AdaptedReconstruction rec(model, config);
    for (std::size_t k = 0; k < r.e.size(); ++k) {
      if (kind == 2 || kind == 3) rec.set_temperature(r.temp[k]);
      const auto est = rec.step(r.e[k], r.d[k]);
      s_hat[k] = est.strain;
      t_hat[k] = est.stress;
      if (k >= settle) {
        const double err = rec.drift().temperature_degc - r.temp[k];
        sq += err * err;
        worst = std::max(worst, std::abs(err));
      }
    }
  }
  Figures f{fit_quality(r.s, s_hat), fit_quality(r.t, t_hat), 0.0, worst};
  f.temperature_rms_k = std::sqrt(sq / static_cast<double>(r.e.size() - settle));
  return f;
}

void print(const char* what, const Figures& f) {
  std::printf(
      "%-22s S_hat %.3f %% (max %.2f %%), T_hat %.3f %% (max %.2f %%), "
      "equivalent temperature error rms %.2f K max %.2f K\n",
      what, 100 * f.strain.nrmse, 100 * f.strain.max, 100 * f.stress.nrmse, 100 * f.stress.max,
      f.temperature_rms_k, f.temperature_max_k);
}

// Measured (seed 21, 25 -> 55 degC over the mix excitation twice, 200 s at 1 kHz; the drift's
// random walk process_noise_per_s 3e-5 since 2026-11-27, docs/adaptation.md):
//   as identified         S_hat 1.757 % (max 6.16 %), T_hat 5.519 % (max 19.39 %)
//   adapted (E, D only)   S_hat 0.274 % (max 0.83 %), T_hat 1.022 % (max 2.81 %),
//                         equivalent temperature 2.34 K RMS, 5.80 K max after the first 20 s
//   recorded temperature  S_hat 0.165 % (max 0.63 %), T_hat 0.709 % (max 2.50 %)
// Issue 24's goal (0.2 % and 0.8 % without the temperature, 0.15 % and 0.6 % with it, 2 K) is
// not reached with the model alone: the bounds below are the measured figures with a margin of
// about 1.3x. With the fitted temperature coefficients, at the end of the test.
TEST(AdaptationAccuracy, WarmingRampWithoutTemperatureInput) {
  const Recorded r = warming_recording(21, 25.0, 55.0, 2);
  const std::size_t settle = 20000;  // 20 s at 1 kHz before the temperature error is counted
  const Figures none = reconstruct(r, 0, settle);
  const Figures adapted = reconstruct(r, 1, settle);
  const Figures measured = reconstruct(r, 2, settle);
  const Figures fitted = reconstruct(r, 3, settle);
  const Figures adapted_fitted = reconstruct(r, 4, settle);
  print("as identified", none);
  print("adapted (E, D only)", adapted);
  print("recorded temperature", measured);
  RecordProperty("S_hat_nrmse_adapted", std::to_string(adapted.strain.nrmse));
  RecordProperty("T_hat_nrmse_adapted", std::to_string(adapted.stress.nrmse));
  EXPECT_LE(adapted.strain.nrmse, 0.0036);
  EXPECT_LE(adapted.strain.max, 0.0108);
  EXPECT_LE(adapted.stress.nrmse, 0.0133);
  EXPECT_LE(adapted.stress.max, 0.0365);
  EXPECT_LE(adapted.temperature_rms_k, 3.05);
  EXPECT_LE(adapted.temperature_max_k, 7.5);
  EXPECT_LE(measured.strain.nrmse, 0.0021);
  EXPECT_LE(measured.strain.max, 0.0082);
  EXPECT_LE(measured.stress.nrmse, 0.0092);
  EXPECT_LE(measured.stress.max, 0.0325);
  // Without adaptation it is far worse (measured 1.757 % and 5.519 %).
  EXPECT_GE(none.strain.nrmse, 0.015);
  EXPECT_GE(none.stress.nrmse, 0.045);
  EXPECT_LT(adapted.strain.nrmse, 0.25 * none.strain.nrmse);
  EXPECT_LT(adapted.stress.nrmse, 0.25 * none.stress.nrmse);
  // With the temperature coefficients fitted on the identification excitation's ramp
  // (model_with_coefficients), measured 0.152 % (max 0.57 %) and 0.591 % (max 2.19 %) with the
  // recorded temperature; 0.175 % (max 0.67 %), 0.621 % (max 2.34 %), 1.58 K RMS, 4.26 K max
  // adapted from E and D with the estimator read through the increments' coefficients (0.177 %,
  // 0.602 %, 2.07 K, 5.71 K with the levels'; 0.208 %, 0.690 %, 2.39 K before the random walk).
  print("recorded, fitted coef", fitted);
  print("adapted, fitted coef", adapted_fitted);
  EXPECT_LE(fitted.strain.nrmse, 0.0020);
  EXPECT_LE(fitted.strain.max, 0.0074);
  EXPECT_LE(fitted.stress.nrmse, 0.0077);
  EXPECT_LE(fitted.stress.max, 0.0285);
  EXPECT_LT(fitted.stress.nrmse, measured.stress.nrmse);
  EXPECT_LE(adapted_fitted.strain.nrmse, 0.0023);
  EXPECT_LE(adapted_fitted.strain.max, 0.0087);
  EXPECT_LE(adapted_fitted.stress.nrmse, 0.0081);
  EXPECT_LE(adapted_fitted.stress.max, 0.0303);
  EXPECT_LE(adapted_fitted.temperature_rms_k, 2.05);
  EXPECT_LE(adapted_fitted.temperature_max_k, 5.5);
  EXPECT_LT(adapted_fitted.stress.nrmse, adapted.stress.nrmse);
  // The estimator's increments see a stronger loop change than the levels (measured -4.604e-3
  // against -3.068e-3 per K; permittivity 3.837e-3 against 3.708e-3 per K).
  const models::TemperatureCoefficients& coefficients = *model_with_coefficients().temperature;
  EXPECT_LT(coefficients.increments.loop_per_k, 1.3 * coefficients.sensor.loop.per_k);
  EXPECT_NEAR(coefficients.increments.linear_per_k, 3.837e-3, 0.3e-3);
}

// Slow random swings about 40 degC (between about 26 and 54 degC, up to 0.5 K/s), the same
// model and validation plant, 300 s (seed 23). Measured (the random walk on, above):
//   as identified         S_hat 1.560 % (max 4.85 %), T_hat 4.942 % (max 16.03 %)
//   adapted (E, D only)   S_hat 0.333 % (max 1.19 %), T_hat 1.181 % (max 3.85 %),
//                         equivalent temperature 3.18 K RMS, 10.29 K max after the first 20 s
//   recorded temperature  S_hat 0.142 % (max 0.61 %), T_hat 0.638 % (max 2.47 %)
// Asserted at about 1.3x; the goal is not reached without the temperature (docs/adaptation.md).
TEST(AdaptationAccuracy, SlowRandomSwingsWithoutTemperatureInput) {
  const Recorded r = warming_recording(23, 25.0, 25.0, 3, true);
  const std::size_t settle = 20000;
  const Figures none = reconstruct(r, 0, settle);
  const Figures adapted = reconstruct(r, 1, settle);
  const Figures measured = reconstruct(r, 2, settle);
  const Figures fitted = reconstruct(r, 3, settle);
  const Figures adapted_fitted = reconstruct(r, 4, settle);
  print("swings, as identified", none);
  print("swings, adapted", adapted);
  print("swings, recorded temp", measured);
  print("swings, fitted coef", fitted);
  print("swings, adapted fitted", adapted_fitted);
  EXPECT_LE(adapted.strain.nrmse, 0.0043);
  EXPECT_LE(adapted.stress.nrmse, 0.0154);
  EXPECT_LE(adapted.temperature_rms_k, 4.15);
  EXPECT_LE(measured.strain.nrmse, 0.0019);
  EXPECT_LE(measured.stress.nrmse, 0.0083);
  EXPECT_GE(none.stress.nrmse, 0.04);
  EXPECT_LT(adapted.strain.nrmse, 0.35 * none.strain.nrmse);
  EXPECT_LT(adapted.stress.nrmse, 0.35 * none.stress.nrmse);
  // With the fitted coefficients, measured 0.123 % and 0.499 % with the recorded temperature;
  // 0.257 %, 0.848 %, 2.74 K RMS (9.30 K max) adapted from E and D with the increments'
  // coefficients (0.273 %, 0.889 %, 3.04 K with the levels'; 0.341 %, 1.090 %, 3.71 K before
  // the random walk; what the rest is made of: docs/adaptation.md).
  EXPECT_LE(fitted.strain.nrmse, 0.0016);
  EXPECT_LE(fitted.stress.nrmse, 0.0065);
  EXPECT_LE(adapted_fitted.strain.nrmse, 0.0033);
  EXPECT_LE(adapted_fitted.stress.nrmse, 0.0110);
  EXPECT_LE(adapted_fitted.temperature_rms_k, 3.6);
}

// A 10-minute hold after the ramp (the field held at 1 MV/m, the load still moving, 55 degC):
// no increment passes the excitation gate, so the estimate does not move at all. Measured: 51.68
// degC at the hold (the estimate lags a 30 K ramp over 100 s by 3.3 K), T_hat RMS error over
// the hold 3.9e5 Pa.
TEST(AdaptationAccuracy, NoDriftOverATenMinuteHold) {
  plant::PlantFile f = warming_plant("reconstruction-validation.yaml", 22);
  plant::Excitation ex = plant::make_excitation("mix", f.excitation, f.plant.sample_rate_hz, 22);
  const std::size_t ramp = ex.size();
  const auto hold = static_cast<std::size_t>(600.0 * f.plant.sample_rate_hz);
  ex.e_v_per_m.resize(ramp + hold, 1.0e6);
  f.excitation.temperature = {25.0, 55.0};
  plant::apply_load_and_temperature(f.excitation, f.plant.sample_rate_hz, ex);
  for (std::size_t k = 0; k < ex.size(); ++k) {
    ex.temp_degc[k] =
        std::min(55.0, 25.0 + 30.0 * static_cast<double>(k) / static_cast<double>(ramp));
  }
  const Recorded r = record(f.plant, ex);
  adaptation::AdaptedReconstruction rec(main_job_model(), adaptation::DriftEstimatorConfig{});
  adaptation::Drift at_hold{};
  std::size_t updates_at_hold = 0;
  double stress_sq = 0.0;
  for (std::size_t k = 0; k < r.e.size(); ++k) {
    const double t_hat = rec.step(r.e[k], r.d[k]).stress;
    if (k == ramp + 1000) {  // the field settled at the hold value
      at_hold = rec.drift();
      updates_at_hold = rec.estimator().updates();
    }
    if (k > ramp) stress_sq += (t_hat - r.t[k]) * (t_hat - r.t[k]);
  }
  std::printf(
      "hold: equivalent temperature %.2f degC at its start, %.2f at its end (true 55); "
      "T_hat RMS error over the hold %.3g Pa\n",
      at_hold.temperature_degc, rec.drift().temperature_degc,
      std::sqrt(stress_sq / static_cast<double>(hold)));
  EXPECT_GT(updates_at_hold, 1000U);
  EXPECT_EQ(rec.estimator().updates(), updates_at_hold);
  EXPECT_EQ(rec.drift().temperature_degc, at_hold.temperature_degc);
  EXPECT_NEAR(rec.drift().temperature_degc, 55.0, 4.5);
}

}  // namespace
}  // namespace selfsense
