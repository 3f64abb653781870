// The independent actuator (diagnosis/independent/actuator.hpp) and a fixed sample of proof
// draws on it (draws.hpp; issue 23, item 4). The generator's physics is checked here against
// figures computed apart from it; the draws assert only what holds by construction (the
// calibrated ratio, finite figures) and print each outcome: the rates the proof asserts are
// measured by tests/bench/diagnosis_draws on 100 draws per effect.
//
// Seeds: this sample uses kSampleSeedBase + i; 900000 + i is the development range.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <numbers>
#include <ostream>
#include <string>
#include <vector>

#include "diagnosis/independent/actuator.hpp"
#include "diagnosis/independent/draws.hpp"

namespace selfsense::independent {
namespace {

constexpr std::uint64_t kSampleSeedBase = 500000;

// The first draw of `effect` from seed `from` on whose form `accept` holds.
template <typename F>
Draw find_draw(Effect effect, F&& accept, std::uint64_t from = 1) {
  for (std::uint64_t seed = from; seed < from + 100; ++seed) {
    Draw d = make_draw(seed, effect);
    if (accept(d)) return d;
  }
  ADD_FAILURE() << "no draw of " << to_string(effect) << " with that form";
  return make_draw(from, effect);
}

double range(const std::vector<double>& x) {
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  return *hi - *lo;
}

TEST(IndependentActuator, SameSeedSameRecording) {
  for (Effect e : kEffects) {
    const Draw a = make_draw(42, e);
    const Draw b = make_draw(42, e);
    EXPECT_EQ(a.form, b.form);
    EXPECT_EQ(describe(a), describe(b));
    for (int x = 0; x < 2; ++x) {
      const Recording ra = record(a, {.excitation = x});
      const Recording rb = record(b, {.excitation = x});
      EXPECT_EQ(ra.e, rb.e) << to_string(e);
      EXPECT_EQ(ra.d, rb.d) << to_string(e);
      EXPECT_EQ(ra.s, rb.s) << to_string(e);
      EXPECT_EQ(ra.t, rb.t) << to_string(e);
      EXPECT_EQ(ra.temp, rb.temp) << to_string(e);
    }
  }
  // Another seed, another bench; the validation excitation is not the identification's.
  const Recording a = record(make_draw(42, Effect::kNone), {});
  EXPECT_NE(a.e, record(make_draw(43, Effect::kNone), {}).e);
  EXPECT_NE(a.e, record(make_draw(42, Effect::kNone), {.excitation = 1}).e);
}

// What the recordings look like: rates, ranges and durations of a piezo stack bench.
TEST(IndependentActuator, RecordingsHaveTheBenchMagnitudes) {
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    const Draw d = make_draw(seed, Effect::kNone);
    EXPECT_GE(d.sample_rate_hz, 1000.0);
    EXPECT_LE(d.sample_rate_hz, 2000.0);
    for (int x = 0; x < 2; ++x) {
      const Recording r = record(d, {.excitation = x});
      const double seconds = r.sample_time * static_cast<double>(r.e.size());
      EXPECT_GE(seconds, 60.0);
      EXPECT_LE(seconds, 90.0);
      EXPECT_LE(r.e.size(), 200000U);
      EXPECT_GT(*std::max_element(r.e.begin(), r.e.end()), 1.5e6);
      EXPECT_LT(*std::max_element(r.e.begin(), r.e.end()), 2.1e6);
      EXPECT_GT(*std::min_element(r.e.begin(), r.e.end()), -0.15e6);
      EXPECT_GT(range(r.d), 0.02);
      EXPECT_LT(range(r.d), 0.08);
      EXPECT_GT(range(r.s), 0.9e-3);
      EXPECT_LT(range(r.s), 2.0e-3);
      EXPECT_LT(*std::max_element(r.t.begin(), r.t.end()), 0.0);  // always compressed
      EXPECT_GT(*std::min_element(r.t.begin(), r.t.end()), -8e6);
      EXPECT_EQ(range(r.temp), 0.0);  // 25 degC without the temperature effect
    }
  }
}

// A triangle sweep 0 -> E_ref -> 0 (third cycle, no stress): the strain loop's width is 10-15 %
// of the stroke as drawn (8-20 % asserted), and each branch is monotone.
TEST(IndependentActuator, PreisachLoopIsTenToFifteenPercentOfTheStroke) {
  constexpr int kPoints = 1000;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    const Draw d = make_draw(seed, Effect::kNone);
    StackModel stack(d.stack);
    std::vector<double> up(kPoints + 1);
    std::vector<double> down(kPoints + 1);
    for (int cycle = 0; cycle < 3; ++cycle) {
      for (int i = 0; i <= kPoints; ++i) {
        up[static_cast<std::size_t>(i)] = stack.step(d.stack.field_ref * i / kPoints, 0.0, {}).s;
      }
      for (int i = kPoints; i >= 0; --i) {
        down[static_cast<std::size_t>(i)] = stack.step(d.stack.field_ref * i / kPoints, 0.0, {}).s;
      }
    }
    double width = 0.0;
    for (std::size_t i = 0; i < up.size(); ++i) {
      width = std::max(width, down[i] - up[i]);
      if (i > 0) {
        EXPECT_GE(up[i], up[i - 1]) << seed;
        EXPECT_GE(down[i], down[i - 1]) << seed;
      }
    }
    const double fraction = width / (up.back() - up.front());
    EXPECT_GE(fraction, 0.08) << seed;
    EXPECT_LE(fraction, 0.20) << seed;
    EXPECT_NEAR(fraction, strain_loop_fraction(d.stack), 0.01) << seed;
    EXPECT_NEAR(up.back() - up.front(), 1.3e-3, 0.25e-3) << seed;  // the stroke
  }
}

// The Preisach class: a minor loop returns to the point it left (wiping out), and the output
// does not depend on the rate.
TEST(IndependentActuator, PreisachReturnsToTheTurningPoint) {
  const Density density;
  Preisach p(density, 2e6);
  p.step(0.0);
  p.step(1.6e6);
  const double left = p.step(0.5e6);
  p.step(1.1e6);
  EXPECT_DOUBLE_EQ(p.step(0.5e6), left);
  p.step(0.8e6);
  p.step(0.6e6);
  p.step(0.9e6);
  EXPECT_DOUBLE_EQ(p.step(0.5e6), left);
  const double top = p.step(1.6e6);
  Preisach q(density, 2e6);
  q.step(0.0);
  for (int i = 1; i <= 100; ++i)
    q.step(1.6e6 * i / 100);  // the same path in small steps
  EXPECT_NEAR(q.step(1.6e6), top, 1e-12);
  EXPECT_GT(top, left);
}

// Leakage through the stack's parallel conductance sigma: the measured charge gains
// sigma * integral(E dt) over the clean one, nothing else changes.
TEST(IndependentActuator, ConductanceLeakageFollowsTheFieldIntegral) {
  const Draw d = find_draw(Effect::kLeakage, [](const Draw& x) { return x.leakage.conductance; });
  const Recording on = record(d, {.noise = false});
  const Recording off = record(d, {.effect = false, .noise = false});
  const double eps = d.stack.permittivity + d.stack.polarization / d.stack.field_ref;
  const double sigma = d.magnitude * eps / d.leakage.tau_s;  // [S/m]
  double integral = 0.0;
  double worst = 0.0;
  for (std::size_t k = 1; k < on.e.size(); ++k) {
    integral += 0.5 * on.sample_time * (on.e[k] + on.e[k - 1]);
    worst = std::max(worst, std::abs(on.d[k] - off.d[k] - sigma * integral));
  }
  EXPECT_GT(sigma * integral, 1e-4);  // visible: several times the noise
  EXPECT_LT(worst, 1e-9 * sigma * integral);
  EXPECT_EQ(on.s, off.s);
  EXPECT_EQ(on.e, off.e);
}

// A high-pass on the charge with tau: m' = D' - m / tau, so the measured charge falls behind the
// clean one by integral(m dt) / tau.
TEST(IndependentActuator, HighPassLeakageLosesChargeAtTheRateOneOverTau) {
  const Draw d = find_draw(Effect::kLeakage, [](const Draw& x) { return !x.leakage.conductance; });
  const Recording on = record(d, {.noise = false});
  const Recording off = record(d, {.effect = false, .noise = false});
  const double tau = d.leakage.tau_s / d.magnitude;
  double integral = 0.0;
  double worst = 0.0;
  for (std::size_t k = 1; k < on.d.size(); ++k) {
    integral += 0.5 * on.sample_time * (on.d[k] + on.d[k - 1]);
    worst = std::max(worst, std::abs(on.d[k] - off.d[k] + integral / tau));
  }
  EXPECT_GT(integral / tau, 1e-4);  // visible: several times the noise
  EXPECT_LT(worst, 1e-3 * integral / tau);
  EXPECT_EQ(on.s, off.s);
}

// Delay: the channel sampled `samples` late.
TEST(IndependentActuator, DelayShiftsByTheDrawnFraction) {
  // On a sine, the cubic interpolation is exact to a part in 1e6 at 20 samples per period.
  constexpr double kW = 2.0 * std::numbers::pi / 20.0;
  std::vector<double> x(400);
  for (std::size_t k = 0; k < x.size(); ++k)
    x[k] = std::sin(kW * static_cast<double>(k));
  for (double samples : {0.37, 1.0, 2.6}) {
    const std::vector<double> y = delayed(x, samples);
    for (std::size_t k = 10; k < x.size() - 10; ++k) {
      EXPECT_NEAR(y[k], std::sin(kW * (static_cast<double>(k) - samples)), 2e-3) << samples;
    }
  }
  // On a recording: the delay that best maps the clean channel onto the delayed one, found on a
  // grid of 0.01 samples with linear interpolation over the smooth stretches.
  for (bool strain : {false, true}) {
    const Draw d =
        find_draw(Effect::kDelay, [&](const Draw& c) { return c.delay.on_strain == strain; });
    const Recording on = record(d, {.noise = false});
    const Recording off = record(d, {.effect = false, .noise = false});
    const std::vector<double>& a = strain ? off.s : off.d;
    const std::vector<double>& b = strain ? on.s : on.d;
    std::vector<std::size_t> smooth;
    for (std::size_t k = 20; k + 1 < a.size(); ++k) {
      const double slope = 0.5 * (a[k + 1] - a[k - 1]);
      if (std::abs(a[k + 1] - 2.0 * a[k] + a[k - 1]) < 0.01 * std::abs(slope)) smooth.push_back(k);
    }
    double best = 0.0;
    double best_sse = std::numeric_limits<double>::infinity();
    for (int i = 0; i <= 1000; ++i) {
      const double delta = 0.01 * i;
      const auto whole = static_cast<std::size_t>(delta);
      const double f = delta - static_cast<double>(whole);
      double sse = 0.0;
      for (std::size_t k : smooth) {
        const double shifted = (1.0 - f) * a[k - whole] + f * a[k - whole - 1];
        sse += (b[k] - shifted) * (b[k] - shifted);
      }
      if (sse < best_sse) {
        best_sse = sse;
        best = delta;
      }
    }
    const double drawn = d.magnitude * d.delay.samples;
    EXPECT_NEAR(best, drawn, 0.05 + 0.02 * drawn) << d.form;
    EXPECT_EQ(strain ? on.d : on.s, strain ? off.d : off.s);
  }
}

// The clean recording of a draw has the same excitation, temperature and noise; only the
// channels the effect moves differ, and only when an effect is on.
TEST(IndependentActuator, TheEffectChangesOnlyItsChannels) {
  for (Effect e : kEffects) {
    const Draw d = make_draw(7, e);
    const Recording on = record(d, {});
    const Recording off = record(d, {.effect = false});
    const Recording zero = record(d, {.scale = 0.0});
    EXPECT_EQ(on.e, off.e);
    EXPECT_EQ(on.t, off.t);
    EXPECT_EQ(on.temp, off.temp);
    EXPECT_EQ(off.d, zero.d);
    EXPECT_EQ(off.s, zero.s);
    bool d_moves = e == Effect::kLeakage || e == Effect::kStress || e == Effect::kTemperature ||
                   e == Effect::kCreepLeakage;
    bool s_moves = e == Effect::kDynamics;
    if (e == Effect::kCreep || e == Effect::kCreepLeakage) {
      d_moves = d_moves || d.creep.on_charge;
      s_moves = s_moves || d.creep.on_strain;
    }
    if (e == Effect::kDelay) (d.delay.on_strain ? s_moves : d_moves) = true;
    if (e == Effect::kStress) {
      s_moves = d.stress.coupling_per_pa != 0.0 || d.stress.loop_per_pa != 0.0;
    }
    if (e == Effect::kTemperature) {
      s_moves = d.temperature.linear_per_k[1] != 0.0 || d.temperature.linear_per_k[2] != 0.0;
    }
    EXPECT_EQ(on.d != off.d, d_moves) << d.form;
    EXPECT_EQ(on.s != off.s, s_moves) << d.form;
    if (e == Effect::kTemperature) {
      EXPECT_GT(range(on.temp), 9.0);
    }
  }
}

// ---- the mechanisms, on development draws -------------------------------------------------

// Each mechanism on the development draw that showed it (seed base 900000), not a proof draw:
// the proof's rates are measured on seed bases never run before (docs/diagnose.md). Every case
// must be named on its channel with at most one extra name and leave at most `excess` of the
// validation error in excess of the clean case's; the comment says what it measures.
struct Mechanism {
  const char* name{""};
  Effect effect{Effect::kNone};
  std::uint64_t seed{0};
  double excess{0.3};
};

// GoogleTest finds this by its name to print a parameter.
void PrintTo(const Mechanism& m, std::ostream* os) {  // NOLINT(readability-identifier-naming)
  *os << m.name;
}

const Mechanism kMechanisms[] = {
    // A stack that warmed while its base was identified on the same recording (a swing of the
    // permittivity, coupling and loop, quadratic in the change): the base bent to the drift, and
    // terms fitted after it carried nothing to new data (excess 0.94x before the
    // re-identification). With the side re-identified with the temperature's terms undone
    // (reidentified.hpp) it is named on D and the excess falls to 0.04x (measured).
    {"WarmingInTheBaseIsNamedWithItsTermsUndone", Effect::kTemperature, 900000},
    // A ramp of the permittivity, coupling and loop (+1.5e-3, +6.7e-4 and -9.8e-4 per K) with the
    // base identified on the same recording: the side re-identified over the whole record with
    // the terms undone kept the drift in its slow creep lags, and validation D stayed at 0.245 %
    // (before 0.304 %, clean 0.015 %: excess 0.79x). The stack stays within 30 % of its
    // temperature range of its start for 21 % of the record, so the side is identified on the
    // record's first third and the terms on all of it: named on D, validation D 0.059 % (excess
    // 0.15x, measured).
    {"WarmingRampIsNamedWithTheSideFromTheRecordsStart", Effect::kTemperature, 900006},
    // Strain sampled 8 samples late, with the base identified on the same recording: its fastest
    // lags bent to the lag, so a delay fitted after it lost on the slow blocks and a mode was
    // named in one stretch (excess 0.65x). With the side re-identified with the delay undone the
    // delay is named on S and the excess falls to 0.00x (measured).
    {"LateStrainInTheBaseIsNamedByAForecast", Effect::kDelay, 900002},
    // D sampled 0.23 samples late, with the base identified on the same recording: its fastest
    // lags took part of the lag in, so the rounds named `delay` on D at 0.17 samples, and the
    // delay after the bent base carried little (validation D 0.079 %, before 0.083 %, clean
    // 0.071 %: excess 0.68x). The side identified with the delay undone fitted the first half
    // 78 % better but forecast the second half worse than the null (a sub-sample delay lives in
    // the fastest moves), so it was not judged a finding of its own. Carried by that side where
    // it fits the record better than the delay after the base (read_later.hpp reads the record
    // back by cubic interpolation), validation D falls to 0.074 % (excess 0.23x, measured).
    {"DelayTheRoundsNamedIsCarriedByTheSideIdentifiedWithIt", Effect::kDelay, 900006},
    // Strain sampled 1.31 samples late, with the base identified on the same recording: over the
    // record neither the delay nor a mode after the base was significant on the blocks, and the
    // local pass named two modes in one stretch of 1 083 samples (260 and 96 Hz; validation S
    // 0.126 -> 0.102 %, clean 0.075 %: excess 0.52x, the wrong physics). The side identified on
    // the first half with 1.19 samples undone leaves 16 % of the null's error there, the best
    // mode undone 17 %, and it forecasts the second half 71 % better (the mode 70 %), at p = 0.038
    // on the blocks, short of the 99 % test. As the simpler form of a lag already named, the
    // delay is carried in the modes' place (the side with it undone fits the record 81 % better
    // than the modes after the base): named `delay` on S, validation S 0.076 % (excess 0.01x,
    // measured).
    {"LateStrainNamedAsAModeInOneStretchIsCarriedAsADelay", Effect::kDelay, 900008},
    // Strain that creeps, with a `hysteresis` base (no creep operators) identified on the same
    // recording: its loop bent to the creep and nothing was named (`consistent`, validation S
    // 0.761 % against 0.055 % clean). With the structure with creep operators judged as a
    // forecast creep is named on S and the excess falls to 0.03x (measured); the improved model
    // is a hysteresis-creep model.
    {"CreepInALoopModelIsNamedByTheStructureWithCreep", Effect::kCreep, 900005},
    // Strain that creeps from the input (5 lags, 0.013..183 s), with a `hysteresis` base: the
    // structure with creep operators forecast S 78 % better (p < 0.001 over twenty blocks) but
    // one block lost 39 %, beyond the fixed 20 % bound, so only the rounds' creep terms were
    // named and validation S stayed at 0.168 % (clean 0.076 %; excess 0.64x). With the bound
    // at the larger of 20 % and the forecast's own share the structure is named and validation
    // S falls to 0.075 % (excess 0.00x, measured). Seed 2100004 is a draw of the proof run on
    // seed base 2100000 (docs/diagnose.md), traced after it.
    {"CreepForecastWithOneStretchWorseIsNamedByItsStructure", Effect::kCreep, 2100004},
    // A fast, heavily damped mode on S (348 Hz, zeta 0.26, at 1-2 kHz), with the base identified
    // on the same recording: in the excitation's band it lags like a delay, the rounds' mode was
    // not significant on the blocks, and the delay's re-identification named `delay` (excess
    // 0.00x, the wrong physics). With the modes around the rounds' one re-identified beside the
    // delay (the mode undone, mode_undone.hpp), the mode fits the first half 1.7x better than
    // the delay and is named (excess 0.13x, measured). Seed 2400008 is a draw of the proof run on
    // seed base 2400000 (docs/diagnose.md), traced after it.
    {"FastDampedModeIsNamedAsAModeNotADelay", Effect::kDynamics, 2400008},
    // Two modes on S (90 Hz, zeta 0.22, share 0.63; 189 Hz, zeta 0.079, share 0.37), with the
    // base identified on the same recording: one mode named in one stretch (99 Hz) carried
    // nothing to new data (validation S 0.374 -> 0.384 %, clean 0.099 %: excess 1.03x). With
    // two modes and a direct path (99 Hz, 0.29, share 0.68; 173 Hz, 0.10, share 0.28; 0.04
    // passing neither) named in that stretch and the side re-identified with both undone,
    // validation S falls to 0.140 % (excess 0.15x, measured). Seed 3800037 is a draw of the
    // proof run on seed base 3800000 (docs/diagnose.md), traced after it.
    {"TwoModesAreUndoneTogether", Effect::kDynamics, 3800037},
    // The converse: S sampled 0.45 samples late (cubic interpolation), with the base identified
    // on the same recording. A second-order low-pass fits the lag best (422 Hz, damping 1.2 at
    // 1054 Hz) and was named `dynamics`, although it has no resonant peak: in the band it is a
    // delay (0.39 samples at DC), as an acquisition chain's filters are. Named `delay` on S where
    // the fitted damping is 1/sqrt(2) or more (excess 0.10x either way, measured).
    {"LowPassWithoutResonanceIsNamedADelay", Effect::kDelay, 900032},
    // Strain sampled 3.7 samples late, with the base identified on the same recording: the base
    // took most of the lag in as loop width, so in the first round a delay fitted after it
    // explained 3 % of the held-out residual and a mode 23 %, short of min_explains, the lag's
    // re-identification (gated on a lag explaining that much) never ran, and the local pass named
    // a mode at 123 Hz (excess 0.64x). With the re-identification judged wherever nothing but
    // lags is named on the channel, `delay` is named on S and the excess falls to 0.05x
    // (measured). Seed 3100014 is a draw of the proof run on seed base 3100000, traced after it.
    {"LagTheBaseTookInAsLoopWidthIsNamedByAForecast", Effect::kDelay, 3100014},
    // Charge that leaks through a high-pass of tau 19 100 s, with the base identified on the
    // same recording: its slowest lags took the leak in over the half it was fitted on, so the
    // leak re-identified on that half fitted it only 11 % better (min_explains is 30 %) although
    // its forecast removed 96 % of the null's error, and nothing was named (validation D 0.073 %
    // against 0.023 % clean). With the backcast beside the forecast (the side identified on the
    // second half predicts the first 93 % better) the leak is named on D and validation D falls
    // to 0.024 % (excess 0.01x, measured; docs/diagnose.md, "Shown both ways"). Seed 2500007 is a
    // draw of the proof run on seed base 2500000, traced after it.
    {"SlowLeakTheBaseTookInIsNamedBothWays", Effect::kLeakage, 2500007},
    // Charge that leaks through a high-pass of tau 3300 s, with a `hysteresis-creep` base: the
    // rounds' creep terms on D took the leak's drift for creep and named `creep` alone, so the
    // leak was never judged (validation D 1.210 % against 1.225 % before and 0.025 % clean:
    // excess 0.99x). With a leak judged wherever the rounds name nothing but creep on D, the
    // leak is named instead and validation D falls to 0.047 % (excess 0.02x, measured).
    {"LeakTheRoundsTookForCreepIsJudgedAsALeak", Effect::kLeakage, 900015},
    // Stress that changes permittivity, coupling and loop, with an affine base identified on the
    // same recording: the rounds named the coupling's change on S alone and validation D stayed
    // at 0.294 % (clean 0.033 %). With the stress-hysteresis structure judged by two-fold
    // cross-validation, taken because it names the stress on D too, validation D falls to
    // 0.092 % (excess 0.22x, measured).
    {"StressInAnAffineBaseIsNamedByCrossValidation", Effect::kStress, 900001},
    // Stress that changes permittivity and loop (k_eps 3.1e-9, k_loop 1.7e-8 /Pa), with an
    // affine base identified on the same recording: the stress-hysteresis structure forecast D
    // 78 % better over the halves and S 35 %, but identified on the whole record it fitted S only
    // 27 % better (min_explains is 30 %), and that refused D's finding too: `consistent`
    // (validation D 0.056 %, clean 0.022 %). With the short channel left unnamed and D kept,
    // the stress is named on D; validation D falls to 0.049 % only (excess 0.79x, measured; the
    // fitted structure carries to the validation's other preload little better than the bent
    // base), asserted at 0.9x. With the loop's change shaped (stress_hysteresis_fit.hpp) the
    // rounds on the structure named asymmetric hysteresis on both channels (D 0.035 %); the
    // generic loop candidates are no longer tried on a structure the diagnosis identified on the
    // record: D 0.047 % (excess 0.75x, measured).
    {"StressNamedOnOneChannelIsNotRefusedByTheOther", Effect::kStress, 900006, 0.9},
    // Stress that changes the permittivity alone (k_eps 6.3e-9 /Pa), with an affine base
    // identified on the same recording: the stress-hysteresis structure forecast D worse than
    // the base's over the halves, and the rounds' terms after the bent base named the stress on D
    // but left validation D at 0.102 % (before 0.142 %, clean 0.031 %: excess 0.64x). With the
    // sensor side identified again with the stress's terms undone (as the temperature's), D
    // falls to 0.030 % (excess 0.00x, measured; docs/diagnose.md, "Stress on D re-identified
    // with its terms undone"). Since one side may be kept (2026-12-06) the stress-hysteresis
    // structure takes D beside S's own side: D 0.064 % (excess 0.29x, measured 2026-12-07).
    // Seed 2600005 is a draw of the proof run on seed base 2600000.
    {"StressOnDTheBaseBentToIsNamedWithItsTermsUndone", Effect::kStress, 2600005},
    // A coupling that falls with compression (d (1 + k T), k = 3.7e-8 /Pa, about 11 % at the
    // recording's -3 MPa preload), with an affine base identified on the same recording: the
    // base's coupling took in the preload's share, so what is left is k (T - T0) r. The stress
    // term T r alone could reach it only by also rescaling y = r + s T, and explained 6 % on S:
    // nothing was named (validation S 1.24 %, clean 0.096 %). With the stress's own column
    // beside it the term is named on S and the excess falls to 0.13x (measured). Seed 1900008
    // is a draw of the proof run on seed base 1900000 (docs/diagnose.md), traced after it.
    {"CouplingThatMovesWithThePreloadIsNamedAboutIt", Effect::kStress, 1900008},
    // Stress that changes permittivity, coupling and loop (k_loop 3.1e-8 /Pa), drawn on S, with
    // an affine base identified on the same recording: the rounds named the stress on D and a
    // generic loop beside it, and the stress-hysteresis structure, judged only where nothing but
    // the stress was named, never ran (validation S 0.378 %, clean 0.055 %: excess 1.00x). A
    // generic loop is part of what that structure re-identifies, so it runs beside one too: it is
    // taken and names the stress on D and S, and validation S falls to 0.082 % (excess 0.08x,
    // measured).
    {"StressBesideAGenericLoopIsJudgedByTheStressStructure", Effect::kStress, 900008},
    // Stress that changes permittivity and loop (k_loop 3.4e-8 /Pa), with an affine base
    // identified on the same recording: over the halves the stress-hysteresis structure
    // forecast D 65 % and S 53 % better, but one block of each half, forecast by the model of the
    // other half, lost 0.89x (D) and 0.63x (S) of the mean block, more than the share it removes,
    // and nothing was named (validation S 0.567 %, clean 0.088 %). Judged with the halves as the
    // unit of harm (the blocks of one half share their model), it names the stress on D and S and
    // validation S falls to 0.177 % (excess 0.19x, measured).
    {"StressStructureIsJudgedByItsHalvesNotByOneStretch", Effect::kStress, 900016},
    // Stress that changes permittivity and loop (k_eps 5.1e-9, k_loop 1.2e-8 /Pa) on D: the
    // rounds named it on D and the sensor side was identified again with the stress's terms
    // undone, but the joint fitted the gain per pascal on the model's output y while the model
    // runs it on the response to the drive alone, y - d T (models/channel_correction.hpp): the
    // model returned was not the one judged (k d T^2 apart), and validation D went from 0.073 to
    // 0.098 % (clean 0.044 %: excess 1.84x). With the joint fitted on the response, D falls to
    // 0.045 % (excess 0.04x, measured).
    {"StressTermsAreFittedAsTheModelRunsThem", Effect::kStress, 900014},
    // A coupling that falls with compression on S alone (k_d 5.3e-8 /Pa: 10-30 % of the stroke
    // over the load), with an affine base identified on the same recording: the base bent so
    // far that the stress terms after it explained 30 % of S's held-out residual with one block
    // 1.9x worse, nothing was named, and the verdict was `consistent` at validation S 1.391 %
    // (clean 0.098 %). A stress candidate led that first round, so the strain side is
    // identified again with the stress's terms undone (read on the response, as the model runs
    // them; read on y the returned model ran 4.4 % of S's range away from the one judged, and
    // validation S went to 6.07 %): named on S, validation S 0.140 % (excess 0.03x, measured).
    // Seed 3800037 is a draw of the proof run on seed base 3800000, traced after it.
    {"StressTheRoundsCouldNotNameIsJudgedWithItsTermsUndone", Effect::kStress, 3800037},
    // Strain that creeps and charge that leaks (a high-pass, tau 6230 s), with a `hysteresis`
    // base: the rounds named creep on D, the structure with creep operators did not forecast D
    // better, and the leak was not judged beside a creep finding (creep D and S named, validation
    // D worse: excess 1.17x). With the leak judged wherever the creep is, it is named on D
    // (forecast: 96 % of the null's error removed) and the rounds no longer name creep there;
    // creep stays named on S (excess 0.52x, measured; asserted at the proof's 0.6x).
    {"LeakBesideCreepOnTheOtherChannelIsNamed", Effect::kCreepLeakage, 900001, 0.6},
    // Charge that creeps and leaks through a conductance on the same channel, with a
    // `hysteresis` base: the creep structure goes first (it fits its half 84 % better), and the
    // leak beside it fitted that half only 2 % better (its slowest lags took the leak in), so
    // only creep was named (validation D 0.062 %, the leak's drift left to new data). Judged by
    // its forecast alone (95 % of the creep structure's error removed) the leak is named beside
    // the creep and validation D falls to 0.028 % (clean 0.079 %; excess 0.00x, measured;
    // asserted at the proof's 0.6x).
    {"LeakBesideCreepOnTheSameChannelIsNamedByItsForecast", Effect::kCreepLeakage, 900002, 0.6},
    // Charge that creeps and leaks (a high-pass, tau 8430 s), with a `hysteresis` base: neither
    // alone forecast D well enough (the creep structure 31 % better with a block lost, the leak
    // not at all), so nothing was named (excess 1.00x). Judged as one forecast, the creep
    // structure with the leak undone removes 98 % of the null's error, 97 % of the creep
    // structure's alone and 96 % of the leak's alone; both are named on D and validation D falls
    // from 0.109 % to 0.027 % (clean 0.021 %; excess 0.07x, measured; asserted at the proof's
    // 0.6x).
    {"CreepAndLeakNeitherAloneAreNamedAsAPair", Effect::kCreepLeakage, 900003, 0.6},
};

class IndependentMechanism : public ::testing::TestWithParam<Mechanism> {};

// The improved model as the runtime runs it reproduces the output its findings were judged on
// (Outcome::model_gap, an nrmse): the same stage code both ways, so equal to rounding.
constexpr double kSameModel = 1e-9;

// Stress that changes coupling and loop (k_d 4e-9, k_loop 5.6e-9 /Pa), drawn on S, with an
// affine base identified on the same recording: the stress-hysteresis structure forecasts S
// better over the halves and D worse, and it replaced both sides or none. With D keeping the
// base's side (models/stress_sides.hpp) the structure is taken for S: named on S (validation S
// 0.116 -> 0.105 %, clean 0.046 %: excess 0.84x, short of the proof's 0.6x) and D keeps the
// first pass's terms on the base's side (0.025 -> 0.022 %, clean 0.020 %; measured). Until
// 2026-12-07 this case was 900012, which the stress's terms fitted on the response now name
// on both channels without the structure (excess 0.13 -> 0.03x).
TEST(IndependentMechanismOneSided, StressOnOneChannelKeepsTheOtherChannelsSide) {
  const Outcome o = run_draw(900028, Effect::kStress);
  std::printf("%s\n", summary(o).c_str());
  EXPECT_TRUE(o.named_right);
  EXPECT_LE(o.extra_names, 1);
  EXPECT_EQ(o.improved, "stress-hysteresis, D plain");
  EXPECT_LT(o.s.after, o.s.before);
  EXPECT_LE(o.d.after, o.d.before);  // the kept side: no harm
  EXPECT_LE(o.model_gap, kSameModel);
}

TEST_P(IndependentMechanism, IsNamedOnItsChannelAndCarriesToNewData) {
  const Mechanism& m = GetParam();
  const Outcome o = run_draw(m.seed, m.effect);
  std::printf("%s\n", summary(o).c_str());
  EXPECT_TRUE(o.named_right);
  EXPECT_LE(o.extra_names, 1);
  EXPECT_LE(o.excess_ratio, m.excess);
  EXPECT_LE(o.model_gap, kSameModel);
}

INSTANTIATE_TEST_SUITE_P(DevelopmentDraws, IndependentMechanism, ::testing::ValuesIn(kMechanisms),
                         [](const ::testing::TestParamInfo<Mechanism>& p) {
                           return std::string(p.param.name);
                         });

// The converse of DelayTheRoundsNamedIsCarriedByTheSideIdentifiedWithIt: D sampled 0.16 samples
// late, with the base identified on the same recording. The rounds named `delay` on D alone (at
// 0.106 samples) and the lag's re-identification was not judged a finding, so the side
// identified with the delay undone was weighed against the delay after the base; here it fits
// the record 5 % worse (the side gains nothing from the undo), so the rounds' finding and model
// stand and the finding says so (excess 0.65x measured, asserted at 0.8x: the rounds' model
// carries at least what it did before the carry existed; the model is the one judged).
TEST(IndependentMechanismCarry, ADelayWhoseCarriedSideFitsWorseKeepsTheRoundsModel) {
  const Outcome o = run_draw(900027, Effect::kDelay);
  std::printf("%s\n", summary(o).c_str());
  ASSERT_TRUE(o.named_right);
  EXPECT_LE(o.extra_names, 1);
  const auto delay = std::find_if(o.findings.begin(), o.findings.end(),
                                  [](const Named& f) { return f.effect == "delay"; });
  ASSERT_NE(delay, o.findings.end());
  std::printf("evidence: %s\n", delay->evidence.c_str());
  EXPECT_NE(delay->evidence.find("which stands"), std::string::npos) << delay->evidence;
  EXPECT_EQ(delay->evidence.find("carried by"), std::string::npos) << delay->evidence;
  EXPECT_LE(o.excess_ratio, 0.8);
  EXPECT_LE(o.model_gap, kSameModel);
}

// ---- a fixed sample of proof draws ---------------------------------------------------------

struct Sample {
  Effect effect{Effect::kNone};
  std::uint64_t seed{0};
};

// GoogleTest finds this by its name to print a parameter.
void PrintTo(const Sample& s, std::ostream* os) {  // NOLINT(readability-identifier-naming)
  *os << to_string(s.effect) << "_" << s.seed;
}

class IndependentDraw : public ::testing::TestWithParam<Sample> {};

TEST_P(IndependentDraw, CalibratesDiagnosesAndValidates) {
  const Sample& s = GetParam();
  const Outcome o = run_draw(s.seed, s.effect);
  std::printf("%s\n", summary(o).c_str());
  for (const Named& e : o.expected)
    std::printf("    expected: %s on %s\n", e.effect.c_str(), e.channel.c_str());
  if (s.effect == Effect::kNone) {
    // Nothing is named on a clean stack (issue 23: "nothing named in the clean case").
    EXPECT_TRUE(o.findings.empty()) << summary(o);
  } else {
    // The calibration reaches the drawn ratio (1.5-5) within 15 % or close to it.
    EXPECT_GE(o.ratio_achieved, 1.3);
    EXPECT_LE(o.ratio_achieved, 6.0);
    EXPECT_FALSE(o.expected.empty());
  }
  for (double v : {o.d.before, o.d.after, o.d.clean, o.s.before, o.s.after, o.s.clean}) {
    EXPECT_TRUE(std::isfinite(v));
    EXPECT_GT(v, 0.0);
    EXPECT_LT(v, 0.2);
  }
  EXPECT_FALSE(o.verdict.empty());
  EXPECT_LE(o.model_gap, kSameModel);
}

INSTANTIATE_TEST_SUITE_P(FixedSample, IndependentDraw,
                         ::testing::Values(Sample{Effect::kNone, kSampleSeedBase},
                                           Sample{Effect::kNone, kSampleSeedBase + 1},
                                           Sample{Effect::kCreep, kSampleSeedBase},
                                           Sample{Effect::kLeakage, kSampleSeedBase},
                                           Sample{Effect::kStress, kSampleSeedBase},
                                           Sample{Effect::kTemperature, kSampleSeedBase},
                                           Sample{Effect::kDynamics, kSampleSeedBase},
                                           Sample{Effect::kDelay, kSampleSeedBase},
                                           Sample{Effect::kCreepLeakage, kSampleSeedBase}),
                         [](const ::testing::TestParamInfo<Sample>& p) {
                           return std::string(to_string(p.param.effect)) + "_" +
                                  std::to_string(p.param.seed);
                         });

}  // namespace
}  // namespace selfsense::independent
