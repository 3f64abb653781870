// Self-sensing and feedforward accuracy on the plant of config/plant/reconstruction.yaml
// (hysteresis and creep on D and S, a varying load, sensor noise of about 1e-4 of range).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "selfsense/identification/fit_quality.hpp"
#include "selfsense/identification/transducer_fit.hpp"
#include "selfsense/models/reconstructor.hpp"
#include "selfsense/operators/hysteresis_creep.hpp"
#include "selfsense/plant/plant.hpp"
#include "selfsense/plant_io/plant_yaml.hpp"

namespace selfsense {
namespace {

using identification::fit_quality;
using identification::FitQuality;

struct Recorded {
  std::vector<double> e, d, s, t;
};

plant::PlantFile benchmark_plant() {
  return plant::load_plant_file(SELFSENSE_SOURCE_DIR "/config/plant/reconstruction.yaml");
}

Recorded record(const plant::PlantConfig& config, const plant::Excitation& ex) {
  plant::Plant p(config);
  Recorded r;
  for (const plant::StepInput& in : ex.inputs()) {
    const plant::StepOutput out = p.step(in);
    r.e.push_back(out.e_meas_v_per_m);
    r.d.push_back(out.d_meas_c_per_m2);
    r.s.push_back(out.s);
    r.t.push_back(out.t_pa);
  }
  return r;
}

Recorded record_kind(const char* kind, std::uint64_t seed) {
  plant::PlantFile f = benchmark_plant();
  f.plant.seed = seed;
  return record(f.plant, plant::make_excitation(kind, f.excitation, f.plant.sample_rate_hz, seed));
}

Recorded record_mix(std::uint64_t seed) {
  return record_kind("mix", seed);
}

models::TransducerModel identify(const Recorded& r, models::Structure structure) {
  return identification::identify({r.e, r.d, r.t, r.s, 1e-3}, structure,
                                  identification::defaults_for(structure));
}

struct Figures {
  FitQuality stress, strain;
};

Figures reconstruct(const models::TransducerModel& model, const Recorded& r) {
  models::Reconstructor rec(model);
  std::vector<double> t_hat;
  std::vector<double> s_hat;
  for (std::size_t k = 0; k < r.e.size(); ++k) {
    const auto est = rec.step(r.e[k], r.d[k]);
    t_hat.push_back(est.stress);
    s_hat.push_back(est.strain);
  }
  return {fit_quality(r.t, t_hat), fit_quality(r.s, s_hat)};
}

// Identified once for the whole suite: seed 1 of the mix excitation.
struct Identified {
  models::TransducerModel hysteresis_creep;
  models::TransducerModel linear;
};

const Identified& identified() {
  static const Identified models = [] {
    const Recorded r = record_mix(1);
    return Identified{identify(r, models::Structure::kHysteresisCreep),
                      identify(r, models::Structure::kLinear)};
  }();
  return models;
}

// The identification excitation (mix, then minor loops of many sizes and offsets), seed 1.
struct IdentifiedOnLoops {
  models::TransducerModel preisach_creep;
  models::TransducerModel hysteresis_creep;
};

const IdentifiedOnLoops& identified_on_loops() {
  static const IdentifiedOnLoops models = [] {
    const Recorded r = record_kind("identification", 1);
    return IdentifiedOnLoops{identify(r, models::Structure::kPreisachCreep),
                             identify(r, models::Structure::kHysteresisCreep)};
  }();
  return models;
}

// A validation excitation generated anew: step levels, sine amplitudes and frequencies, the
// decaying sine, the noise band and the load drawn from `seed` (none equals the fitting
// recording's), inside the field range the fit saw (0 .. 2 MV/m).
Recorded record_new_excitation(std::uint64_t seed) {
  plant::PlantFile f = benchmark_plant();
  std::mt19937_64 rng(seed);
  const auto uniform = [&rng](double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng);
  };
  plant::ExcitationConfig& x = f.excitation;
  x.steps.levels_v_per_m.clear();
  for (int i = 0; i < 6; ++i)
    x.steps.levels_v_per_m.push_back(uniform(0.1e6, 1.95e6));
  x.steps.hold_s = uniform(4.0, 8.0);
  x.sines.offset_v_per_m = uniform(0.9e6, 1.1e6);
  x.sines.amplitudes_v_per_m = {uniform(0.15e6, 0.5e6), uniform(0.5e6, 0.85e6)};
  x.sines.frequencies_hz = {uniform(0.3, 1.2), uniform(1.5, 4.0)};
  x.decaying.amplitude_v_per_m = uniform(0.6e6, 0.85e6);
  x.decaying.offset_v_per_m = uniform(0.95e6, 1.1e6);
  x.decaying.frequency_hz = uniform(0.5, 2.0);
  x.decaying.decay_per_cycle = uniform(0.85, 0.95);
  x.noise.cutoff_hz = uniform(1.0, 5.0);
  x.noise.offset_v_per_m = uniform(0.8e6, 1.2e6);
  x.noise.std_v_per_m = uniform(0.25e6, 0.45e6);
  x.noise.duration_s = 30.0;
  x.load.amplitude_n = uniform(200.0, 450.0);
  x.load.frequency_hz = uniform(0.05, 0.3);
  f.plant.seed = seed;
  return record(f.plant, plant::make_excitation("mix", x, f.plant.sample_rate_hz, seed));
}

TEST(PlantAccuracy, SelfSensingOnAHeldOutRecordingMeetsTheGoals) {
  const Recorded validation = record_mix(2);  // other noise: not used to fit anything
  const Figures hc = reconstruct(identified().hysteresis_creep, validation);
  const Figures lin = reconstruct(identified().linear, validation);
  std::printf(
      "hysteresis-creep: S_hat %.3f %% (max %.3f %%), T_hat %.3f %% (max %.2f %%); "
      "linear: S_hat %.2f %%, T_hat %.2f %%\n",
      100 * hc.strain.nrmse, 100 * hc.strain.max, 100 * hc.stress.nrmse, 100 * hc.stress.max,
      100 * lin.strain.nrmse, 100 * lin.stress.nrmse);
  RecordProperty("S_hat_nrmse", std::to_string(hc.strain.nrmse));
  RecordProperty("T_hat_nrmse", std::to_string(hc.stress.nrmse));
  // Issue 4 goals: S_hat nrmse <= 0.3 %, max <= 1.5 %; T_hat nrmse <= 1.5 %. Measured 0.188 %,
  // 1.23 % and 0.653 % (T_hat max 4.46 %): the bounds below are about 1.3x of that, to catch a
  // regression.
  EXPECT_LE(hc.strain.nrmse, 0.0025);
  EXPECT_LE(hc.strain.max, 0.015);
  EXPECT_LE(hc.stress.nrmse, 0.0085);
  EXPECT_LE(hc.stress.max, 0.058);
  // The linear model on the same data is far worse (measured 3.00 % and 11.07 %; bounded at
  // about 1.3x of that too).
  EXPECT_GT(lin.strain.nrmse, 5.0 * hc.strain.nrmse);
  EXPECT_GT(lin.stress.nrmse, 5.0 * hc.stress.nrmse);
  EXPECT_LE(lin.strain.nrmse, 0.039);
  EXPECT_LE(lin.stress.nrmse, 0.144);
}

// Excitation the fit never saw, the worst of three drawn validations, for the structure whose
// hinges per play were chosen on the fitting recording alone (transducer_fit.hpp), against
// hysteresis-creep identified on the same recording. Issue 7's goal (S_hat <= 0.3 % RMS and
// 1.5 % max, T_hat <= 1.5 %) is met on these three and on the main job's validation
// (docs/results.md). Asserted: the measured worst figures (0.096 %, 0.248 %, 0.411 %) with a
// margin of about 1.35x, hysteresis-creep's (0.387 %, 1.85 %, 1.47 %) with about 1.3x, and the
// improvement (0.25x and 0.28x of hysteresis-creep).
TEST(PlantAccuracy, PreisachClassImprovesSelfSensingOnNewExcitation) {
  Figures worst_pc{};
  Figures worst_hc{};
  const auto worst = [](Figures& w, const Figures& f) {
    w.strain.nrmse = std::max(w.strain.nrmse, f.strain.nrmse);
    w.strain.max = std::max(w.strain.max, f.strain.max);
    w.stress.nrmse = std::max(w.stress.nrmse, f.stress.nrmse);
    w.stress.max = std::max(w.stress.max, f.stress.max);
  };
  const IdentifiedOnLoops& m = identified_on_loops();
  for (const std::uint64_t seed : {11U, 12U, 13U}) {
    const Recorded validation = record_new_excitation(seed);
    const Figures pc = reconstruct(m.preisach_creep, validation);
    const Figures hc = reconstruct(m.hysteresis_creep, validation);
    std::printf(
        "seed %llu: preisach-creep S_hat %.3f %% (max %.3f %%), T_hat %.3f %%; "
        "hysteresis-creep S_hat %.3f %% (max %.3f %%), T_hat %.3f %%\n",
        static_cast<unsigned long long>(seed), 100 * pc.strain.nrmse, 100 * pc.strain.max,
        100 * pc.stress.nrmse, 100 * hc.strain.nrmse, 100 * hc.strain.max, 100 * hc.stress.nrmse);
    worst(worst_pc, pc);
    worst(worst_hc, hc);
  }
  // The sizes chosen on this recording: 8 dead zones per side and 7 hinges per play on both
  // sides. scripts/setup.sh demo gives them (--dead-zones 8 --bias-levels 7) to fit once per side
  // instead of judging every candidate; the same model, checked here so that it stays so.
  for (const auto* side : {&m.preisach_creep.sensor, &m.preisach_creep.actuator}) {
    ASSERT_TRUE(side->has_value());
    const auto& op = (*side)->op;
    EXPECT_EQ(std::max(op.superposition.upper_thresholds.size(),
                       op.superposition.lower_thresholds.size()),
              8U);
    std::vector<double> plays = op.hinges.thresholds;
    std::sort(plays.begin(), plays.end());
    plays.erase(std::unique(plays.begin(), plays.end()), plays.end());
    ASSERT_FALSE(plays.empty());
    EXPECT_EQ(op.hinges.thresholds.size(), 7 * plays.size());
  }
  // The main job's validation (scripts/setup.sh demo): config/plant/reconstruction-validation.yaml,
  // mix seed 2. Measured 0.103 %, 0.284 %, 0.398 %.
  plant::PlantFile main_job =
      plant::load_plant_file(SELFSENSE_SOURCE_DIR "/config/plant/reconstruction-validation.yaml");
  main_job.plant.seed = 2;
  const Figures mj = reconstruct(
      m.preisach_creep,
      record(main_job.plant,
             plant::make_excitation("mix", main_job.excitation, main_job.plant.sample_rate_hz, 2)));
  std::printf("main job's validation: preisach-creep S_hat %.3f %% (max %.3f %%), T_hat %.3f %%\n",
              100 * mj.strain.nrmse, 100 * mj.strain.max, 100 * mj.stress.nrmse);
  EXPECT_LE(mj.strain.nrmse, 0.0014);
  EXPECT_LE(mj.strain.max, 0.0038);
  EXPECT_LE(mj.stress.nrmse, 0.0054);
  RecordProperty("worst_S_hat_nrmse", std::to_string(worst_pc.strain.nrmse));
  RecordProperty("worst_T_hat_nrmse", std::to_string(worst_pc.stress.nrmse));
  EXPECT_LE(worst_pc.strain.nrmse, 0.0013);
  EXPECT_LE(worst_pc.strain.max, 0.0034);
  EXPECT_LE(worst_pc.stress.nrmse, 0.0055);
  EXPECT_LE(worst_pc.strain.nrmse, 0.4 * worst_hc.strain.nrmse);
  EXPECT_LE(worst_pc.stress.nrmse, 0.4 * worst_hc.stress.nrmse);
  std::printf(
      "worst of three: preisach-creep S_hat %.3f %% (max %.3f %%), T_hat %.3f %%; "
      "hysteresis-creep S_hat %.3f %% (max %.3f %%), T_hat %.3f %%\n",
      100 * worst_pc.strain.nrmse, 100 * worst_pc.strain.max, 100 * worst_pc.stress.nrmse,
      100 * worst_hc.strain.nrmse, 100 * worst_hc.strain.max, 100 * worst_hc.stress.nrmse);
  EXPECT_LE(worst_hc.strain.nrmse, 0.005);
  EXPECT_LE(worst_hc.strain.max, 0.024);
  EXPECT_LE(worst_hc.stress.nrmse, 0.019);
}

// Open-loop tracking of a strain trajectory that was not in the identification data, with the
// identified inverse (feedforward) against the linear model's inverse (gain only).
double tracking_nrmse(const models::TransducerModel& model) {
  plant::PlantFile f = benchmark_plant();
  f.excitation.load.amplitude_n = 0.0;  // the static preload only: T is known
  const double stress = f.plant.mechanics.load_force_n / f.plant.geometry.cross_section_m2;
  const models::SideModel& a = *model.actuator;
  operators::HysteresisCreep op(a.op, a.sample_time);
  op.set_history(a.history);
  operators::HysteresisCreepCompensator feedforward(std::move(op), 0.0, 2e6);
  plant::Excitation ex;
  std::vector<double> desired;
  for (int k = 0; k < 40000; ++k) {
    const double t = k * 1e-3;
    const double y = t < 25.0 ? 6e-4 + 4e-4 * std::sin(2 * std::numbers::pi * 0.7 * t)
                              : 5e-4 + 1e-4 * std::floor((t - 25.0) / 3.0);
    desired.push_back(y);
    ex.e_v_per_m.push_back(feedforward.step(y - a.linear_gains.at(0) * stress - a.offset));
  }
  plant::apply_load_and_temperature(f.excitation, f.plant.sample_rate_hz, ex);
  const Recorded r = record(f.plant, ex);
  return fit_quality(desired, r.s).nrmse;
}

TEST(PlantAccuracy, InverseCompensationTracksAHeldOutTrajectory) {
  const double compensated = tracking_nrmse(identified().hysteresis_creep);
  const double uncompensated = tracking_nrmse(identified().linear);
  RecordProperty("compensated_nrmse", std::to_string(compensated));
  RecordProperty("uncompensated_nrmse", std::to_string(uncompensated));
  std::printf("tracking nrmse: compensated %.3f %%, linear inverse %.3f %%\n", 100 * compensated,
              100 * uncompensated);
  // Measured 0.439 % against 6.80 % for the linear inverse: both bounded at about 1.3x.
  EXPECT_LT(compensated, 0.0055);
  EXPECT_LT(compensated, 0.3 * uncompensated);
  EXPECT_LT(uncompensated, 0.088);
}

}  // namespace
}  // namespace selfsense
