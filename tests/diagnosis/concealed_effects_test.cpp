// The diagnosis proof (issue 11): for each effect a correction can model, a recording of the
// plant with that effect switched on and small enough to hide in the raw plots, a base model
// identified on the same plant without it; diagnose names the effect and the validation nrmse
// of the affected channel (a recording with excitation the diagnosis never saw) falls by at
// least half, and with a force sensor the self-sensing T_hat (from E and D alone) follows. A
// clean case names nothing; two effects at once are both named.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <ostream>
#include <span>
#include <string>
#include <vector>

#include "selfsense/diagnosis/diagnosis.hpp"
#include "selfsense/identification/fit_quality.hpp"
#include "selfsense/identification/transducer_fit.hpp"
#include "selfsense/models/runtime_model.hpp"
#include "selfsense/plant/excitation.hpp"
#include "selfsense/plant/plant.hpp"

namespace selfsense {
namespace {

constexpr double kRate = 1000.0;

struct Recorded {
  std::vector<double> e, d, s, t, temp;
  bool has_stress{true};
  [[nodiscard]] diagnosis::Signals signals() const {
    return {e,    d,
            s,    has_stress ? std::span<const double>(t) : std::span<const double>(),
            temp, 1.0 / kRate};
  }
};

// The stack of config/plant/reconstruction.yaml without creep: Preisach hysteresis on D and S,
// a 300 N preload with a load sine (so T varies and the coupling is identifiable), sensor noise.
plant::PlantConfig base_plant() {
  plant::PlantConfig c;
  c.sample_rate_hz = kRate;
  c.hysteresis.enabled = true;
  c.mechanics.load_force_n = -300.0;
  c.sensors.e.noise_std = 200.0;
  c.sensors.d.noise_std = 7.0e-6;
  return c;
}

// Fitting excitation: steps, sines, decaying loops and band-limited noise.
plant::ExcitationConfig fitting_excitation() {
  plant::ExcitationConfig x;
  x.steps.levels_v_per_m = {0.5e6, 1.5e6, 1.0e6, 2.0e6, 0.2e6};
  x.steps.hold_s = 6.0;
  x.sines.amplitudes_v_per_m = {0.4e6, 0.9e6};
  x.sines.frequencies_hz = {0.5, 2.0};
  x.sines.offset_v_per_m = 1.0e6;
  x.sines.cycles = 4;
  x.decaying.amplitude_v_per_m = 0.95e6;
  x.decaying.offset_v_per_m = 1.0e6;
  x.decaying.frequency_hz = 1.0;
  x.decaying.cycles = 20;
  x.noise.duration_s = 25.0;
  x.noise.cutoff_hz = 3.0;
  x.noise.std_v_per_m = 0.4e6;
  x.noise.offset_v_per_m = 1.0e6;
  x.noise.min_v_per_m = 0.0;
  x.noise.max_v_per_m = 2.0e6;
  x.load.amplitude_n = 400.0;
  x.load.frequency_hz = 0.13;
  return x;
}

// Validation: other levels, frequencies, loops and load, never seen by any fit.
plant::ExcitationConfig validation_excitation() {
  plant::ExcitationConfig x = fitting_excitation();
  x.steps.levels_v_per_m = {1.2e6, 0.3e6, 1.8e6, 0.8e6};
  x.steps.hold_s = 5.0;
  x.sines.amplitudes_v_per_m = {0.7e6};
  x.sines.frequencies_hz = {1.3, 3.0};
  x.decaying.frequency_hz = 0.7;
  x.decaying.amplitude_v_per_m = 0.8e6;
  x.noise.cutoff_hz = 2.0;
  x.noise.duration_s = 15.0;
  x.load.amplitude_n = 300.0;
  x.load.frequency_hz = 0.21;
  return x;
}

Recorded record(const plant::PlantConfig& config, const plant::ExcitationConfig& excitation,
                std::uint64_t seed, const std::string& kind = "mix") {
  plant::PlantConfig c = config;
  c.seed = seed;
  const plant::Excitation ex = plant::make_excitation(kind, excitation, kRate, seed);
  plant::Plant p(c);
  Recorded r;
  const bool temperature = excitation.temperature.start_degc != excitation.temperature.end_degc;
  for (const plant::StepInput& in : ex.inputs()) {
    const plant::StepOutput out = p.step(in);
    r.e.push_back(out.e_meas_v_per_m);
    r.d.push_back(out.d_meas_c_per_m2);
    r.s.push_back(out.s);
    r.t.push_back(out.t_pa);
    if (temperature) r.temp.push_back(in.temp_degc);
  }
  return r;
}

// A bench without a force sensor: the stack works free (no preload, no load).
void free_stack(plant::PlantConfig& p, plant::ExcitationConfig& x) {
  p.mechanics.load_force_n = 0.0;
  x.load.amplitude_n = 0.0;
}

// The base model: identified on the same stack and bench with the effect switched off.
models::TransducerModel identify_base(bool stress_sensor, bool hysteresis) {
  plant::PlantConfig p = base_plant();
  p.hysteresis.enabled = hysteresis;
  plant::ExcitationConfig x = fitting_excitation();
  if (!stress_sensor) free_stack(p, x);
  const Recorded r = record(p, x, 11);
  const models::Structure s = models::Structure::kHysteresisCreep;
  return identification::identify(
      {r.e, r.d, stress_sensor ? std::span<const double>(r.t) : std::span<const double>(), r.s,
       1.0 / kRate},
      s, identification::defaults_for(s));
}

// The base a user identifies on the very recording they diagnose (hysteresis-creep).
models::TransducerModel identified_on(const Recorded& r) {
  const models::Structure s = models::Structure::kHysteresisCreep;
  return identification::identify({r.e, r.d, r.t, r.s, 1.0 / kRate}, s,
                                  identification::defaults_for(s));
}

void print_findings(const diagnosis::Result& result) {
  for (const diagnosis::Finding& f : result.findings) {
    std::printf("   %s on %s explains %.2f: %s\n", f.effect.c_str(), f.channel.c_str(), f.explains,
                f.evidence.c_str());
  }
}

const models::TransducerModel& base_model(bool stress_sensor, bool hysteresis) {
  static const models::TransducerModel loaded = identify_base(true, true);
  static const models::TransducerModel free = identify_base(false, true);
  if (!hysteresis) {  // a stack with no hysteresis in the base plant (the hysteresis case)
    static const models::TransducerModel anhysteretic = identify_base(true, false);
    return anhysteretic;
  }
  return stress_sensor ? loaded : free;
}

double nrmse(const std::vector<double>& recorded, const std::vector<double>& model) {
  return identification::fit_quality(recorded, model).nrmse;
}

// Self-sensing: T_hat from the recorded E and D alone (and the temperature when recorded), its
// nrmse against the plant's T.
double stress_estimate_nrmse(const models::TransducerModel& model, const Recorded& r) {
  models::Reconstruction rec(model, models::RuntimeOptions{1.0 / kRate});
  std::vector<double> t_hat(r.e.size());
  for (std::size_t k = 0; k < r.e.size(); ++k) {
    if (!r.temp.empty()) rec.set_temperature(r.temp[k]);
    t_hat[k] = rec.step(r.e[k], r.d[k]).stress;
  }
  return nrmse(r.t, t_hat);
}

struct Expected {
  std::string effect;
  std::string channel;  // "D" or "S": its validation nrmse must fall by at least half
};

struct Case {
  std::string name;
  std::function<void(plant::PlantConfig&, plant::ExcitationConfig&)> effect;
  std::vector<Expected> expected;  // empty: the clean case, nothing named
  bool stress_sensor{true};        // the bench records T
  bool base_hysteresis{true};      // the base plant (and model) has hysteresis
};

// GoogleTest finds this by its name to print a parameter.
void PrintTo(const Case& c, std::ostream* os) {  // NOLINT(readability-identifier-naming)
  *os << c.name;
}

struct Outcome {
  diagnosis::Result result;
  double d_before, d_after, s_before, s_after;  // validation nrmse
  double t_before{0.0}, t_after{0.0};           // ... of T_hat (benches with a force sensor)
};

Outcome run_case(const Case& c) {
  plant::PlantConfig config = base_plant();
  plant::ExcitationConfig fit_x = fitting_excitation();
  plant::ExcitationConfig val_x = validation_excitation();
  if (!c.stress_sensor) {
    free_stack(config, fit_x);
    free_stack(config, val_x);
  }
  config.hysteresis.enabled = c.base_hysteresis;
  c.effect(config, fit_x);
  c.effect(config, val_x);
  Recorded fit = record(config, fit_x, 21);
  Recorded val = record(config, val_x, 22);
  fit.has_stress = val.has_stress = c.stress_sensor;
  const models::TransducerModel& base = base_model(c.stress_sensor, c.base_hysteresis);
  Outcome o{diagnosis::diagnose(base, fit.signals()), 0, 0, 0, 0};
  const diagnosis::Outputs before = diagnosis::simulate(base, val.signals());
  const diagnosis::Outputs after = diagnosis::simulate(o.result.improved, val.signals());
  o.d_before = nrmse(val.d, before.sensed);
  o.d_after = nrmse(val.d, after.sensed);
  o.s_before = nrmse(val.s, before.strain);
  o.s_after = nrmse(val.s, after.strain);
  if (c.stress_sensor) {
    o.t_before = stress_estimate_nrmse(base, val);
    o.t_after = stress_estimate_nrmse(o.result.improved, val);
    std::printf("[%s] validation T_hat %.3g %% -> %.3g %%\n", c.name.c_str(), 100 * o.t_before,
                100 * o.t_after);
  }
  std::printf("[%s] verdict %s; validation D %.3g %% -> %.3g %%, S %.3g %% -> %.3g %%\n",
              c.name.c_str(), diagnosis::to_string(o.result.verdict), 100 * o.d_before,
              100 * o.d_after, 100 * o.s_before, 100 * o.s_after);
  for (const diagnosis::Finding& f : o.result.findings) {
    std::printf("   %s on %s explains %.2f: %s\n", f.effect.c_str(), f.channel.c_str(), f.explains,
                f.evidence.c_str());
    for (const diagnosis::Alternative& a : f.alternatives) {
      std::printf("     alternative: %s (%.2f): %s\n", a.effect.c_str(), a.explains,
                  a.evidence.c_str());
    }
  }
  return o;
}

bool named(const Outcome& o, const Expected& e) {
  return std::any_of(
      o.result.findings.begin(), o.result.findings.end(),
      [&](const diagnosis::Finding& f) { return f.channel == e.channel && f.effect == e.effect; });
}

class ConcealedEffect : public ::testing::TestWithParam<Case> {};

TEST_P(ConcealedEffect, NamedAndValidationErrorHalved) {
  const Case& c = GetParam();
  const Outcome o = run_case(c);
  if (c.expected.empty()) {
    EXPECT_FALSE(o.result.mismatch);
    EXPECT_TRUE(o.result.findings.empty());
    EXPECT_EQ(o.d_after, o.d_before);
    EXPECT_EQ(o.s_after, o.s_before);
    return;
  }
  EXPECT_TRUE(o.result.mismatch);
  // Alternatives explain nearly as much (Options::alternative_share) and say why, in numbers.
  for (const diagnosis::Finding& f : o.result.findings) {
    for (const diagnosis::Alternative& a : f.alternatives) {
      EXPECT_GE(a.explains, 0.8 * f.explains - 1e-12) << a.effect;
      EXPECT_NE(a.evidence.find(" %"), std::string::npos) << a.evidence;
    }
  }
  // Named first: the first finding on each affected channel is a planted effect, not physics
  // the planted one merely resembles.
  for (const Expected& e : c.expected) {
    const auto first =
        std::find_if(o.result.findings.begin(), o.result.findings.end(),
                     [&](const diagnosis::Finding& f) { return f.channel == e.channel; });
    ASSERT_NE(first, o.result.findings.end()) << "nothing named on " << e.channel;
    EXPECT_TRUE(std::any_of(
        c.expected.begin(), c.expected.end(),
        [&](const Expected& x) { return x.channel == e.channel && x.effect == first->effect; }))
        << first->effect << " named first on " << e.channel;
  }
  for (const Expected& e : c.expected) {
    EXPECT_TRUE(named(o, e)) << e.effect << " on " << e.channel << " not named";
    const bool d = e.channel == "D";
    const double before = d ? o.d_before : o.s_before;
    const double after = d ? o.d_after : o.s_after;
    EXPECT_LE(after, 0.5 * before)
        << e.channel << " validation nrmse " << before << " -> " << after;
  }
  // Concealed: the effect stays a few % of range, below the hysteresis (13 % of stroke).
  EXPECT_LT(std::max(o.d_before, o.s_before), 0.05);
  // What the model got right stays right: no channel gets worse on the validation data.
  EXPECT_LE(o.d_after, o.d_before * 1.02);
  EXPECT_LE(o.s_after, o.s_before * 1.02);
  // Self-sensing gains what the sensed channel gains: T_hat from E and D alone falls with a
  // physics named on D (measured 0.10-0.47x) and never gets worse.
  if (c.stress_sensor) {
    EXPECT_LE(o.t_after, o.t_before * 1.02);
    const bool on_sensed = std::any_of(c.expected.begin(), c.expected.end(),
                                       [](const Expected& e) { return e.channel == "D"; });
    if (on_sensed) {
      EXPECT_LE(o.t_after, 0.6 * o.t_before);
    }
  }
}

void leakage(plant::PlantConfig& p, plant::ExcitationConfig&) {
  p.charge_amplifier.leakage_enabled = true;
  p.charge_amplifier.leakage_tau_s = 1500.0;
}
void sensor_delay(plant::PlantConfig& p, plant::ExcitationConfig&) {
  p.sensors.d.delay_samples = 4;
}
void strain_creep(plant::PlantConfig& p, plant::ExcitationConfig&) {
  p.creep.enabled = true;
  p.creep.d_weights.assign(p.creep.tau_s.size(), 0.0);
}
// A tenth of the plant's usual loop width on both channels, with this asymmetry.
void thin_loop(plant::PlantConfig& p, double asymmetry) {
  p.hysteresis.enabled = true;
  p.hysteresis.d_amplitude_c_per_m2 *= 0.1;
  p.hysteresis.s_amplitude *= 0.1;
  p.hysteresis.asymmetry = asymmetry;
}
// Dielectric creep: the polarization keeps moving after a step of the field (D only).
void charge_creep(plant::PlantConfig& p, plant::ExcitationConfig&) {
  p.creep.enabled = true;
  p.creep.s_weights.assign(p.creep.tau_s.size(), 0.0);
}
void permittivity(plant::PlantConfig& p, plant::ExcitationConfig&) {
  p.permittivity.enabled = true;
  p.permittivity.linear_coefficient = 0.05;
  p.permittivity.quadratic_coefficient = 0.03;
}
void stress_coupling(plant::PlantConfig& p, plant::ExcitationConfig&) {
  p.stress.enabled = true;
  p.stress.d_coefficient_per_pa = 4e-9;
  p.stress.hysteresis_coefficient_per_pa = 0.0;
  p.stress.permittivity_coefficient_per_pa = 0.0;
}

// Charge drive (D imposed, E sensed) on a free sample, as a disc on a charge bench, without
// hysteresis (so the charge-drive structure, linear in D, is exact for the clean sample): the
// base model is identified without electrostriction; with it, the strain follows the square of
// the imposed polarization.
TEST(ConcealedEffectChargeDrive, ElectrostrictionIsNamedOnTheStrain) {
  plant::PlantConfig config = base_plant();
  config.hysteresis.enabled = false;
  plant::ExcitationConfig fit_x = fitting_excitation();
  plant::ExcitationConfig val_x = validation_excitation();
  free_stack(config, fit_x);
  free_stack(config, val_x);
  const Recorded clean = record(config, fit_x, 11);
  const models::Structure structure = models::Structure::kChargeDrive;
  const models::TransducerModel base =
      identification::identify({clean.d, clean.e, {}, clean.s, 1.0 / kRate}, structure,
                               identification::defaults_for(structure));
  config.electrostriction.enabled = true;
  config.electrostriction.q_m4_per_c2 = 0.02;
  const Recorded fit = record(config, fit_x, 21);
  const Recorded val = record(config, val_x, 22);
  const auto charge_drive = [](const Recorded& r) {
    return diagnosis::Signals{r.d, r.e, r.s, {}, {}, 1.0 / kRate};
  };
  const diagnosis::Result result = diagnosis::diagnose(base, charge_drive(fit));
  ASSERT_FALSE(result.findings.empty());
  const diagnosis::Finding& first = result.findings.front();
  EXPECT_EQ(first.effect, "electrostriction");
  EXPECT_EQ(first.channel, "S");
  // The evidence names its coefficients as numbers (no format directive left in the text).
  EXPECT_NE(first.evidence.find("D^3"), std::string::npos) << first.evidence;
  EXPECT_EQ(first.evidence.find("3g"), std::string::npos) << first.evidence;
  const double before = nrmse(val.s, diagnosis::simulate(base, charge_drive(val)).strain);
  const double after = nrmse(val.s, diagnosis::simulate(result.improved, charge_drive(val)).strain);
  std::printf("[charge drive electrostriction] %s; validation S %.3g %% -> %.3g %%\n",
              first.evidence.c_str(), 100 * before, 100 * after);
  EXPECT_LE(after, 0.5 * before);
}

// Creep that only the large steps show, as on a poling bench (the disc's holds in
// docs/diagnose.md): holds after steps of very different size, and a polarization that settles
// within seconds at the value the quasi-static model knows (lags of D with weights w_j:
// D_rec = D + sum_j w_j (z_j - D), z_j' = (D - z_j) / tau_j). Alternate time blocks judge it
// where no large step falls; held out one at a time, the holds name it.
Recorded settling_holds(std::vector<double> levels, double hold_s, bool creep, std::uint64_t seed) {
  plant::PlantConfig config = base_plant();
  config.hysteresis.enabled = false;  // the anhysteretic base: its static curve is right
  plant::ExcitationConfig x = fitting_excitation();
  x.steps.levels_v_per_m = std::move(levels);
  x.steps.hold_s = hold_s;
  x.load.amplitude_n = 0.0;  // a constant preload: the charge moves with the field alone
  Recorded r = record(config, x, seed, "steps");
  if (!creep) return r;
  // Creep is linear in log time: lags spread evenly over the decades it spans (0.03-3 s).
  constexpr std::array<double, 5> kTau{0.03, 0.1, 0.3, 1.0, 3.0};  // [s]
  constexpr double kWeight = 0.012;                                // of the step, per lag
  std::array<double, 5> z{};
  z.fill(r.d.front());
  for (double& d : r.d) {
    double settling = 0.0;
    for (std::size_t j = 0; j < z.size(); ++j) {
      z[j] += -std::expm1(-1.0 / (kRate * kTau[j])) * (d - z[j]);
      settling += kWeight * (z[j] - d);
    }
    d += settling;
  }
  return r;
}

TEST(ConcealedEffectHolds, CreepAfterLargeStepsIsNamedOnHeldOutHolds) {
  const Recorded fit = settling_holds(
      {1.0e6, 1.005e6, 2.0e6, 1.995e6, 1.99e6, 0.1e6, 0.105e6, 0.11e6}, 20.0, true, 31);
  const Recorded val =
      settling_holds({0.5e6, 0.505e6, 1.8e6, 1.795e6, 0.3e6, 0.305e6}, 15.0, true, 32);
  const models::TransducerModel& base = base_model(true, false);
  const diagnosis::Result result = diagnosis::diagnose(base, fit.signals());
  print_findings(result);
  const double before = nrmse(val.d, diagnosis::simulate(base, val.signals()).sensed);
  const double after = nrmse(val.d, diagnosis::simulate(result.improved, val.signals()).sensed);
  std::printf("[creep after large steps] validation D %.3g %% -> %.3g %%\n", 100 * before,
              100 * after);
  ASSERT_FALSE(result.findings.empty());
  const diagnosis::Finding& first = result.findings.front();
  EXPECT_EQ(first.effect, "creep");
  EXPECT_EQ(first.channel, "D");
  EXPECT_NE(first.evidence.find("judged on held-out holds"), std::string::npos) << first.evidence;
  EXPECT_LE(after, 0.5 * before);
  // Without the settling the same bench names nothing (the holds name nothing by chance).
  const Recorded clean = settling_holds(
      {1.0e6, 1.005e6, 2.0e6, 1.995e6, 1.99e6, 0.1e6, 0.105e6, 0.11e6}, 20.0, false, 31);
  EXPECT_FALSE(diagnosis::diagnose(base, clean.signals()).mismatch);
}

// A bench of steps and holds only. Alternate time blocks cut each hold in two, so a hysteresis
// operator that draws each hold's level from the other half of the same hold passed them and made
// the validation 4x (mix base) to 13x (base identified on steps) worse; the held-out holds refuse
// it. Creep of the charge, planted in the plant, is still named.
// A base identified on the very recording it is diagnosed on (the user's usual case) has absorbed
// what its own terms can imitate: its residual is orthogonal to them over the record, so the
// coupling's change with stress, fitted on the fitting blocks alone, loses on the held-out ones
// (the first rounds name nothing). Fitted beside a refit of the model's own loop it is named
// (validation S 2.48 -> 0.911 %); the stress-hysteresis structure, cross-validated over the
// record's halves, explains more of S (97 %) and is taken since it may replace a channel's
// findings where it explains more (docs/diagnose.md): 2.48 -> 0.33 %. Either way the finding says
// the base took the stress in. The same bench without the effect names nothing.
TEST(ConcealedEffectAbsorbed, StressCouplingInTheBaseIsNamedBesideItsOwnLoop) {
  plant::PlantConfig p = base_plant();
  plant::ExcitationConfig x = fitting_excitation();
  stress_coupling(p, x);
  p.stress.d_coefficient_per_pa = 2e-8;
  const Recorded fit = record(p, x, 41);
  const Recorded val = record(p, validation_excitation(), 42);
  const models::TransducerModel base = identified_on(fit);
  const diagnosis::Result result = diagnosis::diagnose(base, fit.signals());
  print_findings(result);
  const double before = nrmse(val.s, diagnosis::simulate(base, val.signals()).strain);
  const double after = nrmse(val.s, diagnosis::simulate(result.improved, val.signals()).strain);
  std::printf("[stress coupling absorbed by the base] validation S %.3g %% -> %.3g %%\n",
              100 * before, 100 * after);
  const auto named =
      std::find_if(result.findings.begin(), result.findings.end(), [](const diagnosis::Finding& f) {
        return f.effect == "stress_dependence" && f.channel == "S";
      });
  ASSERT_NE(named, result.findings.end());
  EXPECT_TRUE(named->evidence.find("absorbed") != std::string::npos ||
              named->evidence.find("bent its own operators") != std::string::npos)
      << named->evidence;
  EXPECT_LE(after, 0.18 * before);  // measured 2.48 % -> 0.33 % (0.133x)

  const Recorded clean = record(base_plant(), fitting_excitation(), 41);
  EXPECT_FALSE(diagnosis::diagnose(identified_on(clean), clean.signals()).mismatch);
}

// The charge amplifier's leak in a base identified on the same recording: the base's creep
// operators imitate it over that record, so no correction after the model wins it back on
// alternate blocks. The structure identified on the first half with the leak undone forecasts
// the second half better than the structure identified on D as recorded: named, and the model
// re-identified with the leak undone predicts new excitation better. The clean bench, its base
// identified on itself, names nothing.
TEST(ConcealedEffectReidentified, LeakInTheBaseIsNamedByAForecast) {
  plant::PlantConfig p = base_plant();
  plant::ExcitationConfig x = fitting_excitation();
  leakage(p, x);
  const Recorded fit = record(p, x, 43);
  const Recorded val = record(p, validation_excitation(), 44);
  const models::TransducerModel base = identified_on(fit);
  const diagnosis::Result result = diagnosis::diagnose(base, fit.signals());
  print_findings(result);
  const double before = nrmse(val.d, diagnosis::simulate(base, val.signals()).sensed);
  const double after = nrmse(val.d, diagnosis::simulate(result.improved, val.signals()).sensed);
  std::printf("[leak absorbed by the base] validation D %.3g %% -> %.3g %%\n", 100 * before,
              100 * after);
  const auto named = std::find_if(
      result.findings.begin(), result.findings.end(),
      [](const diagnosis::Finding& f) { return f.effect == "charge_leakage" && f.channel == "D"; });
  ASSERT_NE(named, result.findings.end());
  EXPECT_NE(named->evidence.find("forecast"), std::string::npos) << named->evidence;
  EXPECT_LE(after, 0.5 * before);

  const Recorded clean = record(base_plant(), fitting_excitation(), 43);
  EXPECT_FALSE(diagnosis::diagnose(identified_on(clean), clean.signals()).mismatch);
}

// Where the recording's temperature moves, the side is re-identified with the temperature's terms
// undone and judged on held-out blocks (reidentified.hpp). A clean stack whose temperature column
// ramps by 20 K without acting on it, its base identified on that recording, names nothing.
TEST(ConcealedEffectReidentified, TemperatureThatActsOnNothingIsNotNamed) {
  plant::ExcitationConfig x = fitting_excitation();
  x.temperature.start_degc = 22.0;
  x.temperature.end_degc = 42.0;
  const Recorded clean = record(base_plant(), x, 45);
  ASSERT_FALSE(clean.temp.empty());
  const diagnosis::Result result = diagnosis::diagnose(identified_on(clean), clean.signals());
  print_findings(result);
  EXPECT_FALSE(result.mismatch);
}

TEST(ConcealedEffectHolds, HysteresisThatOnlyDrawsTheHoldLevelsIsNotNamed) {
  const auto holds = [](std::vector<double> levels, double hold_s, bool creep, std::uint64_t seed) {
    plant::PlantConfig config = base_plant();
    plant::ExcitationConfig x = fitting_excitation();
    x.steps.levels_v_per_m = std::move(levels);
    x.steps.hold_s = hold_s;
    x.load.amplitude_n = 0.0;
    if (creep) charge_creep(config, x);
    return record(config, x, seed, "steps");
  };
  const Recorded fit =
      holds({1.0e6, 0.3e6, 1.8e6, 0.6e6, 1.3e6, 0.1e6, 1.6e6, 0.9e6}, 6.0, true, 31);
  const Recorded val = holds({0.5e6, 1.5e6, 0.2e6, 1.9e6, 0.7e6, 1.1e6}, 5.0, true, 32);
  const Recorded steps = holds(
      {0.4e6, 1.6e6, 0.8e6, 2.0e6, 0.2e6, 1.2e6, 1.9e6, 0.6e6, 1.4e6, 0.0, 1.0e6, 1.7e6, 0.3e6},
      4.0, false, 30);
  const models::Structure structure = models::Structure::kHysteresisCreep;
  const models::TransducerModel on_steps =
      identification::identify({steps.e, steps.d, steps.t, steps.s, 1.0 / kRate}, structure,
                               identification::defaults_for(structure));
  for (const bool mix_base : {true, false}) {
    const models::TransducerModel& base = mix_base ? base_model(true, true) : on_steps;
    const diagnosis::Result result = diagnosis::diagnose(base, fit.signals());
    const diagnosis::Outputs before = diagnosis::simulate(base, val.signals());
    const diagnosis::Outputs after = diagnosis::simulate(result.improved, val.signals());
    const double d_before = nrmse(val.d, before.sensed);
    const double d_after = nrmse(val.d, after.sensed);
    std::printf("[steps and holds, base identified on %s] validation D %.3g %% -> %.3g %%\n",
                mix_base ? "the mix" : "steps", 100 * d_before, 100 * d_after);
    for (const diagnosis::Finding& f : result.findings) {
      std::printf("   %s on %s explains %.2f: %s\n", f.effect.c_str(), f.channel.c_str(),
                  f.explains, f.evidence.c_str());
      EXPECT_NE(f.effect, "hysteresis");
      EXPECT_NE(f.effect, "asymmetric_hysteresis");
    }
    EXPECT_LE(d_after, 1.02 * d_before);
    EXPECT_LE(nrmse(val.s, after.strain), 1.02 * nrmse(val.s, before.strain));
    if (mix_base) {
      ASSERT_FALSE(result.findings.empty());
      EXPECT_EQ(result.findings.front().effect, "creep");
      EXPECT_EQ(result.findings.front().channel, "D");
      EXPECT_LE(d_after, 0.5 * d_before);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(
    Plant, ConcealedEffect,
    ::testing::Values(
        Case{"clean", [](plant::PlantConfig&, plant::ExcitationConfig&) {}, {}},
        Case{"charge_leakage", leakage, {{"charge_leakage", "D"}}},
        Case{"offset",
             [](plant::PlantConfig& p, plant::ExcitationConfig&) {
               p.charge_amplifier.drift_enabled = true;
               p.charge_amplifier.offset_c = 4e-6;
               p.charge_amplifier.drift_c_per_s = 0.0;
               p.charge_amplifier.random_walk_c_per_sqrt_s = 0.0;
             },
             {{"offset", "D"}}},
        Case{"delay", sensor_delay, {{"delay", "D"}}},
        Case{"dynamics",
             [](plant::PlantConfig& p, plant::ExcitationConfig& x) {
               p.mechanics.enabled = true;
               p.mechanics.resonance_hz = 150.0;
               p.mechanics.damping_ratio = 0.05;
               x.noise.cutoff_hz = 60.0;
             },
             {{"dynamics", "S"}},
             false},
        Case{"creep", strain_creep, {{"creep", "S"}}},
        Case{"creep_of_the_charge", charge_creep, {{"creep", "D"}}},
        Case{"temperature_dependence",
             [](plant::PlantConfig& p, plant::ExcitationConfig& x) {
               p.temperature.enabled = true;
               x.temperature.start_degc = 20.0;
               x.temperature.end_degc = 45.0;
             },
             {{"temperature_dependence", "D"}}},
        Case{"stress_dependence",
             stress_coupling,
             {{"stress_dependence", "S"}, {"stress_dependence", "D"}}},
        Case{"permittivity_nonlinearity", permittivity, {{"permittivity_nonlinearity", "D"}}},
        // A stack whose base model (and plant) had no hysteresis: a tenth of the plant's usual
        // loop width appears on both channels, its shape changing with the offset and one end
        // saturating (the plant's bias density and asymmetry): hinges on the plays, the
        // Preisach class, model it.
        Case{"asymmetric_hysteresis",
             [](plant::PlantConfig& p, plant::ExcitationConfig&) { thin_loop(p, 0.6); },
             {{"asymmetric_hysteresis", "D"}, {"asymmetric_hysteresis", "S"}},
             true,
             false},
        // The same stack with a symmetric loop and a flat bias density (the Preisach plane
        // uniform along the bias: the Prandtl-Ishlinskii class): plays of the drive model it.
        Case{"hysteresis",
             [](plant::PlantConfig& p, plant::ExcitationConfig&) {
               thin_loop(p, 0.0);
               p.hysteresis.bias_sigma_v_per_m = 2.5e6;
             },
             {{"hysteresis", "D"}, {"hysteresis", "S"}},
             true,
             false},
        Case{"electrostriction",
             [](plant::PlantConfig& p, plant::ExcitationConfig&) {
               p.electrostriction.enabled = true;
               p.electrostriction.q_m4_per_c2 = 0.02;
             },
             {{"electrostriction", "S"}}},
        Case{"leakage_and_creep",
             [](plant::PlantConfig& p, plant::ExcitationConfig& x) {
               leakage(p, x);
               strain_creep(p, x);
             },
             {{"charge_leakage", "D"}, {"creep", "S"}}},
        Case{"delay_and_permittivity",
             [](plant::PlantConfig& p, plant::ExcitationConfig& x) {
               sensor_delay(p, x);
               permittivity(p, x);
             },
             {{"delay", "D"}, {"permittivity_nonlinearity", "D"}}},
        Case{"stress_and_leakage",
             [](plant::PlantConfig& p, plant::ExcitationConfig& x) {
               stress_coupling(p, x);
               leakage(p, x);
             },
             {{"stress_dependence", "S"}, {"stress_dependence", "D"}, {"charge_leakage", "D"}}}),
    [](const ::testing::TestParamInfo<Case>& param) { return param.param.name; });

}  // namespace
}  // namespace selfsense
