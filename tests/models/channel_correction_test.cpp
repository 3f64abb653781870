// Corrections a diagnosis adds (models/channel_correction.hpp) as the runtime runs them:
// forward in the simulation, inverted in the reconstruction, saved and restored, written to and
// read from model files, refused by name where no inverse exists.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "selfsense/model_io/model_yaml.hpp"
#include "selfsense/models/runtime_model.hpp"
#include "support/allocation_counter.hpp"
#include "support/transducer_data.hpp"

namespace selfsense::models {
namespace {

constexpr double kTs = 1e-4;

ChannelCorrection sensed_correction() {
  ChannelCorrection c;
  c.gain = 0.02;
  c.offset = 1.5e-3;
  c.temperature_reference_degc = 25.0;
  c.temperature_gain_per_k = 1e-3;
  c.temperature_offset_per_k = 2e-5;
  c.temperature_drive_per_k = 1e-11;
  c.drive_quadratic = 1e-15;
  c.drive_cubic = -2e-22;
  c.drive_linear = 3e-10;              // the linear play of hysteresis
  c.creep_eigenvalues = {200.0, 5.0};  // lags of the sensor's response to the drive alone
  c.creep_weights = {0.02, -0.01};
  c.leakage_tau_s = 0.5;
  c.delay_s = 3.5 * kTs;
  c.hysteresis_thresholds = {2e5, 5e5};  // hysteresis and asymmetric_hysteresis
  c.hysteresis_weights = {1e-9, -4e-10};
  c.hinge_thresholds = {0.0, 5e5};
  c.hinge_levels = {1.2e6, 8e5};
  c.hinge_weights = {3e-10, -2e-10};
  c.temperature_gain_per_k2 = 2e-5;  // quadratic in the temperature change
  c.temperature_offset_per_k2 = 1e-7;
  c.temperature_drive_per_k2 = 2e-13;
  c.temperature_stress_per_k = 1e-13;  // the coupling moves with the temperature [C/m^2/(Pa K)]
  c.temperature_stress_per_k2 = -2e-15;
  c.drive_integral_per_s = 3e-9;            // a parallel conductance's current [S/m]
  c.drive_creep_eigenvalues = {50.0, 2.0};  // creep driven by the input
  c.drive_creep_weights = {1e-10, 2e-10};
  c.stress_gain_per_pa = 2e-9;         // stress dependence of each part of the response
  c.stress_drive_per_pa = 7e-17;       // [C/m^2 / (V/m Pa)]
  c.stress_linear_per_pa = 1e-13;      // [C/m^2 / Pa]
  c.stress_quadratic_per_pa2 = 1e-20;  // [C/m^2 / Pa^2]
  return c;
}

ChannelCorrection strain_correction() {
  ChannelCorrection c;
  c.gain = -0.01;
  c.stress_gain_per_pa = 3e-9;
  c.sensed_quadratic = 2e-3;
  c.creep_eigenvalues = {100.0, 10.0, 1.0};
  c.creep_weights = {0.01, 0.012, 0.015};
  c.dynamics_frequency_hz = 800.0;
  c.dynamics_damping = 0.1;
  c.dynamics_direct = 0.05;  // a share of the strain passes no mode
  c.dynamics2_frequency_hz = 2000.0;
  c.dynamics2_damping = 0.05;
  c.dynamics2_share = 0.2;
  c.hysteresis_thresholds = {3e5};
  c.hysteresis_weights = {2e-11};
  c.hinge_thresholds = {3e5};
  c.hinge_levels = {9e5};
  c.hinge_weights = {1e-11};
  return c;
}

TransducerModel corrected_model() {
  TransducerModel m = test::typical_transducer(kTs);
  m.sensed_correction = sensed_correction();
  m.strain_correction = strain_correction();
  return m;
}

// The reconstruction undoes what the simulation added on the sensed channel: from the
// simulated D (leakage, delay, gain, offset, temperature linear and quadratic, polynomial, plays,
// creep of the response and of the drive, the field's integral) it recovers the stress that
// drove the simulation, a delay later.
TEST(ChannelCorrection, ReconstructionInvertsTheSensedCorrection) {
  TransducerModel m = corrected_model();
  m.strain_correction.reset();
  const test::TransducerData data = test::transducer_data(m, 4000, kTs, 3);
  Simulation sim(m);
  Reconstruction rec(m);
  sim.set_temperature(31.0);
  rec.set_temperature(31.0);
  double worst = 0.0;
  double range = 0.0;
  std::vector<double> t_hat;
  for (std::size_t k = 0; k < data.e.size(); ++k) {
    const Simulation::Output out = sim.step(data.e[k], data.t[k]);
    t_hat.push_back(rec.step(data.e[k], out.sensed).stress);
    range = std::max(range, std::abs(data.t[k]));
  }
  // D is 3.5 samples late; the reconstruction delays E to match, so T_hat[k] is T at k - 3.5.
  for (std::size_t k = 100; k < data.e.size(); ++k) {
    const double truth = 0.5 * (data.t[k - 3] + data.t[k - 4]);
    worst = std::max(worst, std::abs(t_hat[k] - truth));
  }
  EXPECT_LT(worst, 0.02 * range);
}

TEST(ChannelCorrection, ForwardCorrectionChangesTheOutputAsWritten) {
  TransducerModel base = test::typical_transducer(kTs);
  TransducerModel with_offset = base;
  ChannelCorrection c;
  c.gain = 0.1;
  c.offset = 2e-3;
  with_offset.sensed_correction = c;
  Simulation a(base);
  Simulation b(with_offset);
  for (int k = 0; k < 200; ++k) {
    const double e = 1e6 + 5e5 * std::sin(0.05 * k);
    const double y = a.step(e, -1e6).sensed;
    EXPECT_NEAR(b.step(e, -1e6).sensed, 1.1 * y + 2e-3, 1e-12);
  }
}

// The play terms by their definition: w_0 x + sum w_i (p_i - x) + sum c_h max(0, p_{r_h} - b_h).
TEST(ChannelCorrection, PlayTermsAddWhatTheirDefinitionSays) {
  ChannelCorrection c;
  c.drive_linear = 0.7;
  c.hysteresis_thresholds = {0.1, 0.3};
  c.hysteresis_weights = {2.0, -0.5};
  c.hinge_thresholds = {0.0, 0.3};
  c.hinge_levels = {0.4, 0.2};
  c.hinge_weights = {1.5, 3.0};
  CorrectionStage stage(c, kTs);
  double p1 = 0.0;
  double p3 = 0.0;
  for (int k = 0; k < 400; ++k) {
    const double x = std::sin(0.05 * k) * (1.0 - 0.002 * k);
    if (k == 0) p1 = p3 = x;
    p1 = std::min(std::max(p1, x - 0.1), x + 0.1);
    p3 = std::min(std::max(p3, x - 0.3), x + 0.3);
    const double expected = 0.7 * x + 2.0 * (p1 - x) - 0.5 * (p3 - x) +
                            1.5 * std::max(x - 0.4, 0.0) + 3.0 * std::max(p3 - 0.2, 0.0);
    CorrectionStage::Inputs in;
    in.y = 0.25;
    in.response = 0.25;
    in.drive = x;
    ASSERT_NEAR(stage.step(in), 0.25 + expected, 1e-12) << k;
  }
  ChannelCorrection unknown = c;
  unknown.hinge_thresholds = {0.2, 0.3};
  std::string why;
  EXPECT_FALSE(unknown.is_valid("corrections.sensed", &why));
  EXPECT_NE(why.find("corrections.sensed.hinge_thresholds[0]"), std::string::npos) << why;
}

// Electrostriction: S gains Q P^2 with P the model's sensed response to the drive alone,
// D - d T (the stress part of D is no polarization), in the simulation and the reconstruction.
TEST(ChannelCorrection, ElectrostrictionReadsTheSensedResponseWithoutTheStressPart) {
  TransducerModel base = test::typical_transducer(kTs);
  base.sensed_correction.reset();
  base.strain_correction.reset();
  TransducerModel with = base;
  ChannelCorrection c;
  c.sensed_quadratic = 0.02;
  with.strain_correction = c;
  const double d = base.sensor->linear_gains.front();
  ASSERT_NE(d, 0.0);
  Simulation a(base);
  Simulation b(with);
  Reconstruction rec(with);
  Reconstruction rec_base(base);
  for (int k = 0; k < 300; ++k) {
    const double e = 1e6 + 8e5 * std::sin(0.03 * k);
    const double t = -2e7 + 1e7 * std::sin(0.011 * k);
    const Simulation::Output plain = a.step(e, t);
    const double p = plain.sensed - d * t;
    const Simulation::Output out = b.step(e, t);
    ASSERT_NEAR(out.strain, plain.strain + 0.02 * p * p, 1e-12) << k;
    const double s_hat = rec.step(e, out.sensed).strain;
    const Reconstruction::Estimate plain_hat = rec_base.step(e, plain.sensed);
    ASSERT_NEAR(s_hat, plain_hat.strain + 0.02 * p * p, 1e-9) << k;
  }
}

TEST(ChannelCorrection, StateSavedAndRestoredContinuesBitIdentically) {
  const TransducerModel m = corrected_model();
  const test::TransducerData data = test::transducer_data(m, 1000, kTs, 4);
  Simulation sim(m);
  SavedState state = sim.make_saved_state();
  for (std::size_t k = 0; k < 500; ++k)
    static_cast<void>(sim.step(data.e[k], data.t[k]));
  ASSERT_TRUE(sim.save_state(state));
  std::vector<Simulation::Output> first;
  for (std::size_t k = 500; k < 1000; ++k)
    first.push_back(sim.step(data.e[k], data.t[k]));
  ASSERT_EQ(sim.restore_state(state), RestoreResult::kOk);
  for (std::size_t k = 500; k < 1000; ++k) {
    const Simulation::Output again = sim.step(data.e[k], data.t[k]);
    EXPECT_EQ(again.strain, first[k - 500].strain) << k;
    EXPECT_EQ(again.sensed, first[k - 500].sensed) << k;
  }
  // A model without the corrections is another model.
  Simulation plain(test::typical_transducer(kTs));
  EXPECT_EQ(plain.restore_state(state), RestoreResult::kWrongModel);
}

// The reconstruction's own state (leakage inverse, the drive's delay line) is saved too.
TEST(ChannelCorrection, ReconstructionStateSavedAndRestoredContinuesBitIdentically) {
  const TransducerModel m = corrected_model();
  const test::TransducerData data = test::transducer_data(m, 1000, kTs, 6);
  Simulation sim(m);
  std::vector<double> d;
  for (std::size_t k = 0; k < data.e.size(); ++k)
    d.push_back(sim.step(data.e[k], data.t[k]).sensed);
  Reconstruction rec(m);
  SavedState state = rec.make_saved_state();
  for (std::size_t k = 0; k < 500; ++k)
    static_cast<void>(rec.step(data.e[k], d[k]));
  ASSERT_TRUE(rec.save_state(state));
  std::vector<Reconstruction::Estimate> first;
  for (std::size_t k = 500; k < 1000; ++k)
    first.push_back(rec.step(data.e[k], d[k]));
  for (std::size_t k = 0; k < 37; ++k)
    static_cast<void>(rec.step(data.e[k], d[k]));  // disturb
  ASSERT_EQ(rec.restore_state(state), RestoreResult::kOk);
  for (std::size_t k = 500; k < 1000; ++k) {
    const Reconstruction::Estimate again = rec.step(data.e[k], d[k]);
    EXPECT_EQ(again.stress, first[k - 500].stress) << k;
    EXPECT_EQ(again.strain, first[k - 500].strain) << k;
  }
}

// The worst stress error of the model's reconstruction on its own simulated D, and of the same
// model without its sensed correction, over a drive with a moving load.
struct StressErrors {
  double worst{0.0};
  double worst_ignorant{0.0};
  double range{0.0};
};

StressErrors stress_errors(const TransducerModel& m) {
  const test::TransducerData data = test::transducer_data(m, 3000, kTs, 8);
  Simulation sim(m);
  Reconstruction rec(m);
  TransducerModel plain = m;
  plain.sensed_correction.reset();
  Reconstruction ignorant(plain);
  StressErrors e;
  for (std::size_t k = 0; k < data.e.size(); ++k) {
    const double d = sim.step(data.e[k], data.t[k]).sensed;
    e.worst = std::max(e.worst, std::abs(rec.step(data.e[k], d).stress - data.t[k]));
    e.worst_ignorant =
        std::max(e.worst_ignorant, std::abs(ignorant.step(data.e[k], d).stress - data.t[k]));
    e.range = std::max(e.range, std::abs(data.t[k]));
  }
  return e;
}

// D = h + d T + q T^2 (a coupling that changes with stress): the reconstruction solves the
// quadratic and recovers T, and S_hat follows.
TEST(ChannelCorrection, StressQuadraticIsSolvedInTheReconstruction) {
  TransducerModel m = test::typical_transducer(kTs);
  ChannelCorrection c;
  c.stress_quadratic_per_pa2 = 4e-9 * m.sensor->linear_gains.front();  // d k, k = 4e-9 / Pa
  m.sensed_correction = c;
  const StressErrors e = stress_errors(m);
  EXPECT_LT(e.worst, 1e-6 * e.range);
  EXPECT_GT(e.worst_ignorant, 100.0 * e.worst);  // the term matters: without it T_hat is off
}

// Stress dependence of each part of D: D = h + d T + (k_r r + k_x x + k_1) T + q T^2 with r the
// response to the field alone (loop and permittivity), x the field (the permittivity alone) and
// k_1 a coupling change: linear in T given the field, so the reconstruction solves it after the
// kernel and recovers T; without the terms T_hat is off.
TEST(ChannelCorrection, StressTermsOfTheSensedChannelAreSolvedInTheReconstruction) {
  TransducerModel m = test::typical_transducer(kTs);
  const double d = m.sensor->linear_gains.front();
  ChannelCorrection c;
  c.stress_gain_per_pa = 5e-9;            // the response +0.5 % per MPa
  c.stress_drive_per_pa = 4e-9 * 1.8e-8;  // a permittivity of 1.8e-8 F/m, +0.4 % per MPa
  c.stress_linear_per_pa = 3e-3 * d;      // the coupling +0.3 %
  c.stress_quadratic_per_pa2 = 4e-9 * d;  // ... and bending with T
  m.sensed_correction = c;
  std::string why;
  ASSERT_TRUE(c.invertible("corrections.sensed", &why)) << why;
  const StressErrors e = stress_errors(m);
  EXPECT_LT(e.worst, 1e-6 * e.range);
  EXPECT_GT(e.worst_ignorant, 100.0 * e.worst);
}

// A coupling that moves with the temperature, (d + k1 dtheta + k2 dtheta^2) T on D: the
// reconstruction divides it out after the kernel (solve_stress), the stress comes back exactly.
TEST(ChannelCorrection, TemperatureStressCouplingIsSolvedInTheReconstruction) {
  TransducerModel m = test::typical_transducer(kTs);
  const double d = m.sensor->linear_gains.front();
  ChannelCorrection c;
  c.temperature_gain_per_k = 2e-3;
  c.temperature_drive_per_k2 = 1e-13;
  c.temperature_stress_per_k = 3e-3 * d;  // the coupling +0.3 %/K apart from the loop's 0.2 %/K
  c.temperature_stress_per_k2 = -4e-5 * d;
  m.sensed_correction = c;
  const test::TransducerData data = test::transducer_data(m, 3000, kTs, 8);
  TransducerModel plain = m;
  plain.sensed_correction->temperature_stress_per_k = 0.0;
  plain.sensed_correction->temperature_stress_per_k2 = 0.0;
  Simulation sim(m);
  Reconstruction rec(m);
  Reconstruction ignorant(plain);
  double worst = 0.0;
  double worst_ignorant = 0.0;
  double range = 0.0;
  for (std::size_t k = 0; k < data.e.size(); ++k) {
    const double theta = 25.0 + 15.0 * static_cast<double>(k) / 3000.0;  // warming by 15 K
    sim.set_temperature(theta);
    rec.set_temperature(theta);
    ignorant.set_temperature(theta);
    const double dk = sim.step(data.e[k], data.t[k]).sensed;
    worst = std::max(worst, std::abs(rec.step(data.e[k], dk).stress - data.t[k]));
    worst_ignorant =
        std::max(worst_ignorant, std::abs(ignorant.step(data.e[k], dk).stress - data.t[k]));
    range = std::max(range, std::abs(data.t[k]));
  }
  EXPECT_LT(worst, 1e-6 * range);
  EXPECT_GT(worst_ignorant, 100.0 * worst);  // the terms matter: without them T_hat is off
}

TEST(ChannelCorrection, ModelFileRoundTripKeepsEveryTermAndTheIdentity) {
  const TransducerModel m = corrected_model();
  const TransducerModel back = model_from_string(model_to_string(m));
  ASSERT_TRUE(back.sensed_correction && back.strain_correction);
  EXPECT_EQ(back.sensed_correction->delay_s, m.sensed_correction->delay_s);
  EXPECT_EQ(back.sensed_correction->temperature_drive_per_k,
            m.sensed_correction->temperature_drive_per_k);
  EXPECT_EQ(back.strain_correction->creep_weights, m.strain_correction->creep_weights);
  EXPECT_EQ(*back.sensed_correction, *m.sensed_correction);  // every term, the newer ones too
  EXPECT_EQ(*back.strain_correction, *m.strain_correction);
  EXPECT_EQ(parameter_hash(back), parameter_hash(m));
  EXPECT_NE(parameter_hash(back), parameter_hash(test::typical_transducer(kTs)));
}

TEST(ChannelCorrection, BadValuesAreNamedByKey) {
  TransducerModel m = test::typical_transducer(kTs);
  m.strain_correction = strain_correction();
  m.strain_correction->creep_weights.pop_back();
  std::string why;
  EXPECT_FALSE(m.is_valid(&why));
  EXPECT_NE(why.find("corrections.strain.creep_weights"), std::string::npos) << why;
  const std::string text = model_to_string(corrected_model());
  const std::string bad = text.substr(0, text.find("leakage_tau_s")) + "leakage_tau_s: -1" +
                          text.substr(text.find('\n', text.find("leakage_tau_s")));
  try {
    static_cast<void>(model_from_string(bad, "m.yaml"));
    FAIL() << "a negative leakage time constant was accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("corrections.sensed.leakage_tau_s"), std::string::npos)
        << e.what();
  }
}

TEST(ChannelCorrection, ReconstructionRefusesASensedCorrectionWithoutInverse) {
  TransducerModel m = test::typical_transducer(kTs);
  ChannelCorrection c;
  c.dynamics_frequency_hz = 900.0;
  c.dynamics_damping = 0.1;
  m.sensed_correction = c;
  try {
    Reconstruction rec(m);
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("corrections.sensed.dynamics_frequency_hz"),
              std::string::npos);
  }
  EXPECT_NO_THROW(Simulation sim(m));
}

// An actuator-only model has no sensed output (NaN): the strain correction must not take it in.
TEST(ChannelCorrection, ActuatorOnlyModelStaysFinite) {
  TransducerModel m = test::typical_transducer(kTs);
  m.sensor.reset();
  ChannelCorrection c;
  c.dynamics_frequency_hz = 900.0;
  c.dynamics_damping = 0.1;
  m.strain_correction = c;
  Simulation sim(m);
  for (int k = 0; k < 100; ++k) {
    EXPECT_TRUE(std::isfinite(sim.step(1e6 * std::sin(0.1 * k), 0.0).strain)) << k;
  }
}

// Two modes in parallel and a direct path: w = (1 - a - b) H1[v] + a v + b H2[v], each mode the
// one-mode stage's filter; unity DC gain (a step settles at its own height).
TEST(ChannelCorrection, TwoModesAreTheirSharesOfEachModeAndOfTheDirectPath) {
  ChannelCorrection both;
  both.dynamics_frequency_hz = 300.0;
  both.dynamics_damping = 0.05;
  both.dynamics_direct = 0.1;
  both.dynamics2_frequency_hz = 700.0;
  both.dynamics2_damping = 0.1;
  both.dynamics2_share = 0.3;
  ChannelCorrection first;
  first.dynamics_frequency_hz = 300.0;
  first.dynamics_damping = 0.05;
  ChannelCorrection second;
  second.dynamics_frequency_hz = 700.0;
  second.dynamics_damping = 0.1;
  CorrectionStage mixed(both, kTs);
  CorrectionStage h1(first, kTs);
  CorrectionStage h2(second, kTs);
  double largest = 0.0;
  for (std::size_t k = 0; k < 4000; ++k) {
    const double v = k < 10 ? 0.0 : 1.0 + 0.1 * std::sin(2e-2 * static_cast<double>(k));
    const double w = mixed.filter(v);
    const double expected = 0.6 * h1.filter(v) + 0.1 * v + 0.3 * h2.filter(v);
    EXPECT_NEAR(w, expected, 1e-12) << k;
    largest = std::max(largest, std::abs(w - v));
  }
  EXPECT_GT(largest, 0.05);  // the modes ring: not the identity
  CorrectionStage step(both, kTs);
  double settled = 0.0;
  for (std::size_t k = 0; k < 20000; ++k)
    settled = step.filter(k < 10 ? 0.0 : 1.0);
  EXPECT_NEAR(settled, 1.0, 1e-9);
  // A share needs its mode.
  ChannelCorrection orphan;
  orphan.dynamics2_share = 0.2;
  std::string why;
  EXPECT_FALSE(orphan.is_valid("corrections.strain", &why));
  EXPECT_NE(why.find("corrections.strain.dynamics2_share"), std::string::npos) << why;
  orphan = ChannelCorrection{};
  orphan.dynamics_direct = 0.1;
  EXPECT_FALSE(orphan.is_valid("corrections.strain", &why));
  EXPECT_NE(why.find("corrections.strain.dynamics_direct"), std::string::npos) << why;
}

// The delay line: below one sample a linear read (no later sample exists), from one sample on a
// cubic through four samples, which does not low-pass a fast component the way a linear read
// does (its error at 0.3 rad per sample, t = 1/2: about 2e-4 of the amplitude against 1.1e-2).
TEST(ChannelCorrection, DelayReadsBetweenSamplesLinearlyBelowOneSampleAndByCubicFromOne) {
  constexpr double kOmega = 0.3;  // rad per sample
  const auto sine = [](double k) { return std::sin(kOmega * k); };
  for (const double samples : {0.5, 2.5, 3.25}) {
    ChannelCorrection c;
    c.delay_s = samples * kTs;
    CorrectionStage stage(c, kTs);
    double worst = 0.0;
    for (std::size_t k = 0; k < 400; ++k) {
      const double kd = static_cast<double>(k);
      const double out = stage.filter(sine(kd));
      if (k < 10) continue;
      if (samples < 1.0) {
        EXPECT_NEAR(out, 0.5 * (sine(kd) + sine(kd - 1.0)), 1e-12) << k;
      } else {
        worst = std::max(worst, std::abs(out - sine(kd - samples)));
      }
    }
    if (samples >= 1.0) {
      EXPECT_LT(worst, 5e-4) << samples;  // linear: 1.1e-2 at t = 1/2
    }
  }
  // Whole samples read the sample itself.
  ChannelCorrection whole;
  whole.delay_s = 2.0 * kTs;
  CorrectionStage stage(whole, kTs);
  for (std::size_t k = 0; k < 40; ++k) {
    const double out = stage.filter(sine(static_cast<double>(k)));
    if (k >= 2) {
      EXPECT_DOUBLE_EQ(out, sine(static_cast<double>(k) - 2.0)) << k;
    }
  }
}

TEST(ChannelCorrection, StepsDoNotAllocate) {
  TransducerModel m = corrected_model();
  const test::TransducerData data = test::transducer_data(m, 2000, kTs, 5);
  m.strain_correction->sensed_quadratic = 0.0;
  Simulation sim(m);
  Reconstruction rec(m);
  SavedState state = sim.make_saved_state();
  double sink = 0.0;
  test::AllocationCounter counter;
  for (std::size_t k = 0; k < data.e.size(); ++k) {
    sim.set_temperature(25.0 + 1e-3 * static_cast<double>(k));
    const Simulation::Output out = sim.step(data.e[k], data.t[k]);
    sink += rec.step(data.e[k], out.sensed).strain;
    static_cast<void>(sim.save_state(state));
    static_cast<void>(sim.restore_state(state));
  }
  EXPECT_EQ(counter.count(), 0U);
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
}  // namespace selfsense::models
