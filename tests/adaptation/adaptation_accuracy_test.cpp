// Issue 24's proof for the sensorless slice: the main job's model (preisach-creep, identified
// on config/plant/reconstruction.yaml at 25 degC) reconstructs a recording of the same plant
// under excitation it never saw (config/plant/reconstruction-validation.yaml, other seed) while
// the stack warms 25 -> 55 degC with the coefficients of config/plant/temperature.yaml; with the
// drift estimated from E and D alone, without it, and with the recorded temperature.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "selfsense/adaptation/adapted_reconstruction.hpp"
#include "selfsense/identification/fit_quality.hpp"
#include "selfsense/identification/transducer_fit.hpp"
#include "selfsense/models/reconstructor.hpp"
#include "selfsense/model_io/model_yaml.hpp"
#include <filesystem>
#include <cstdlib>
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
    if (const char* cache = std::getenv("ADAPT_CACHE"); cache && std::filesystem::exists(cache))
      return models::load_model(cache);
    plant::PlantFile f =
        plant::load_plant_file(SELFSENSE_SOURCE_DIR "/config/plant/reconstruction.yaml");
    f.plant.seed = 1;
    const Recorded r = record(f.plant, plant::make_excitation("identification", f.excitation,
                                                              f.plant.sample_rate_hz, 1));
    auto m = identification::identify(
        {r.e, r.d, r.t, r.s, 1.0 / f.plant.sample_rate_hz}, models::Structure::kPreisachCreep,
        identification::defaults_for(models::Structure::kPreisachCreep));
    if (const char* cache = std::getenv("ADAPT_CACHE")) models::save_model(m, cache, {});
    return m;
  }();
  return model;
}

// The validation plant with config/plant/temperature.yaml's coefficients, the mix excitation
// repeated `repeats` times, the temperature ramping start -> end over the whole recording.
Recorded warming_recording(std::uint64_t seed, double start_degc, double end_degc, int repeats) {
  plant::PlantFile f =
      plant::load_plant_file(SELFSENSE_SOURCE_DIR "/config/plant/reconstruction-validation.yaml");
  const plant::PlantFile heat =
      plant::load_plant_file(SELFSENSE_SOURCE_DIR "/config/plant/temperature.yaml");
  f.plant.temperature = heat.plant.temperature;
  f.plant.seed = seed;
  plant::Excitation one = plant::make_excitation("mix", f.excitation, f.plant.sample_rate_hz, seed);
  plant::Excitation ex = one;
  for (int i = 1; i < repeats; ++i) {
    ex.e_v_per_m.insert(ex.e_v_per_m.end(), one.e_v_per_m.begin(), one.e_v_per_m.end());
  }
  f.excitation.temperature = {start_degc, end_degc};
  plant::apply_load_and_temperature(f.excitation, f.plant.sample_rate_hz, ex);
  return record(f.plant, ex);
}

struct Figures {
  FitQuality strain, stress;
  double temperature_rms_k{0.0};
  double temperature_max_k{0.0};
};

// kind: 0 the model as identified, 1 adapted from E and D, 2 the recorded temperature.
Figures reconstruct(const Recorded& r, int kind, std::size_t settle) {
  const models::TransducerModel& model = main_job_model();
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
    config.frozen = kind == 2;
    if (const char* v = std::getenv("ADAPT_MEM")) config.memory_updates = std::atof(v);
    if (const char* v = std::getenv("ADAPT_STEP")) config.min_field_step_v_per_m = std::atof(v);
    if (const char* v = std::getenv("ADAPT_INT")) config.max_interval_s = std::atof(v);
    adaptation::AdaptedReconstruction rec(model, config);
    for (std::size_t k = 0; k < r.e.size(); ++k) {
      if (kind == 2) rec.set_temperature(r.temp[k]);
      const auto est = rec.step(r.e[k], r.d[k]);
      s_hat[k] = est.strain;
      t_hat[k] = est.stress;
      if (kind == 1 && k % 10000 == 0)
        std::printf("t %.0f s: temp %.1f eq %.1f eps %.4f loop %.4f updates %zu\n", static_cast<double>(k) * 1e-3,
                    r.temp[k], rec.drift().temperature_degc, rec.drift().permittivity,
                    rec.drift().loop, rec.estimator().updates());
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
  std::printf("%-22s S_hat %.3f %% (max %.2f %%), T_hat %.3f %% (max %.2f %%), "
              "equivalent temperature error rms %.2f K max %.2f K\n",
              what, 100 * f.strain.nrmse, 100 * f.strain.max, 100 * f.stress.nrmse,
              100 * f.stress.max, f.temperature_rms_k, f.temperature_max_k);
}

TEST(AdaptationAccuracy, WarmingRampWithoutTemperatureInput) {
  const Recorded r = warming_recording(21, 25.0, 55.0, 2);
  const std::size_t settle = 20000;  // 20 s at 1 kHz before the temperature error is counted
  const Figures none = std::getenv("ADAPT_ONLY") ? Figures{} : reconstruct(r, 0, settle);
  const Figures adapted = reconstruct(r, 1, settle);
  const Figures measured = std::getenv("ADAPT_ONLY") ? Figures{} : reconstruct(r, 2, settle);
  print("as identified", none);
  print("adapted (E, D only)", adapted);
  print("recorded temperature", measured);
}

}  // namespace
}  // namespace selfsense
