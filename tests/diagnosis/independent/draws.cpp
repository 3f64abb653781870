// One draw of the diagnosis proof on the independent actuator (draws.hpp).
#include "diagnosis/independent/draws.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <tuple>
#include <utility>

#include "selfsense/diagnosis/diagnosis.hpp"
#include "selfsense/identification/fit_quality.hpp"
#include "selfsense/identification/transducer_fit.hpp"

namespace selfsense::independent {
namespace {

constexpr double kTolerance = 0.15;  // calibration: achieved ratio within 15 % of the target
constexpr int kMaxSteps = 6;         // identifications per calibrated quantity
constexpr double kMaxFactor = 30.0;  // largest change of the magnitude per step

models::Structure structure_for(Effect e) {
  return e == Effect::kCreep || e == Effect::kCreepLeakage ? models::Structure::kHysteresis
                                                           : models::Structure::kHysteresisCreep;
}

diagnosis::Signals signals(const Recording& r) {
  return {r.e, r.d, r.s, r.t, r.temp, r.sample_time};
}

double nrmse(const std::vector<double>& recorded, const std::vector<double>& model) {
  return identification::fit_quality(recorded, model).nrmse;
}

// A base identified on a recording and its fit nrmse there.
struct Fit {
  models::TransducerModel model{};
  double d{0.0};
  double s{0.0};
};

Fit fit(const Recording& r, models::Structure structure) {
  Fit f{identification::identify({r.e, r.d, r.t, r.s, r.sample_time}, structure,
                                 identification::defaults_for(structure))};
  const diagnosis::Outputs o = diagnosis::simulate(f.model, signals(r));
  f.d = nrmse(r.d, o.sensed);
  f.s = nrmse(r.s, o.strain);
  return f;
}

struct Channels {
  bool d{false};
  bool s{false};
};

Channels creep_channels(const CreepForm& c) {
  return {c.on_charge, c.on_strain};
}

// The channels an effect moves.
Channels affected(const Draw& draw) {
  switch (draw.effect) {
    case Effect::kNone:
      return {};
    case Effect::kCreep:
      return creep_channels(draw.creep);
    case Effect::kLeakage:
      return {true, false};
    case Effect::kStress: {
      const StressForm& f = draw.stress;
      return {true, f.coupling_per_pa != 0.0 || f.loop_per_pa != 0.0};
    }
    case Effect::kTemperature: {
      const TemperatureForm& f = draw.temperature;
      return {true, f.linear_per_k[1] != 0.0 || f.linear_per_k[2] != 0.0};
    }
    case Effect::kDynamics:
      return {false, true};
    case Effect::kDelay:
      return {!draw.delay.on_strain, draw.delay.on_strain};
    case Effect::kCreepLeakage:
      return {true, draw.creep.on_strain};
  }
  return {};
}

double ratio(const Fit& f, const Fit& clean, Channels c) {
  return std::max(c.d ? f.d / clean.d : 0.0, c.s ? f.s / clean.s : 0.0);
}

// Of the channels, the one whose residual grew most.
std::string primary(const Fit& f, const Fit& clean, Channels c) {
  if (!c.d) return "S";
  if (!c.s) return "D";
  return f.d / clean.d >= f.s / clean.s ? "D" : "S";
}

struct Trial {
  double m{1.0};
  double ratio{0.0};
  Fit fit{};
  Recording recording{};
};

// The effect's share of the residual, about proportional to the magnitude.
double excess(double ratio) {
  return 0.5 * std::log(std::max(ratio * ratio - 1.0, 1e-6));
}

class Calibration {
 public:
  Calibration(const Fit& clean, models::Structure structure, double target)
      : clean_(clean), structure_(structure), target_(target) {}

  // Secant steps on log m; `set` puts magnitude m into a copy of the draw.
  Trial run(const Draw& draw, const std::function<void(Draw&, double)>& set, double m0,
            Channels channels) {
    const double goal = excess(target_);
    Trial a = evaluate(draw, set, m0, channels);
    Trial best = a;
    double slope = 1.0;
    for (int i = 1; i < kMaxSteps && !close(best.ratio); ++i) {
      const double step =
          std::clamp((goal - excess(a.ratio)) / slope, -std::log(kMaxFactor), std::log(kMaxFactor));
      Trial b = evaluate(draw, set, a.m * std::exp(step), channels);
      const double dl = std::log(b.m / a.m);
      if (std::abs(dl) > 1e-9) {
        slope = std::clamp((excess(b.ratio) - excess(a.ratio)) / dl, 0.2, 5.0);
      }
      if (distance(b.ratio) < distance(best.ratio)) best = b;
      a = std::move(b);
    }
    return best;
  }
  [[nodiscard]] int steps() const { return steps_; }

 private:
  Trial evaluate(const Draw& draw, const std::function<void(Draw&, double)>& set, double m,
                 Channels channels) {
    Draw d = draw;
    set(d, m);
    Trial t;
    t.m = m;
    t.recording = record(d, {});
    t.fit = fit(t.recording, structure_);
    t.ratio = ratio(t.fit, clean_, channels);
    ++steps_;
    return t;
  }
  [[nodiscard]] double distance(double r) const { return std::abs(std::log(r / target_)); }
  [[nodiscard]] bool close(double r) const { return std::abs(r / target_ - 1.0) <= kTolerance; }

  const Fit& clean_;
  models::Structure structure_;
  double target_;
  int steps_{0};
};

// Calibrates the draw's magnitudes in place; returns the trial at them and the channel the
// creep shows most on (creep draws).
std::pair<Trial, std::string> calibrate(Draw& draw, const Fit& clean, Calibration& cal) {
  const auto set_primary = [](Draw& d, double m) { d.magnitude = m; };
  if (draw.effect != Effect::kCreepLeakage) {
    Trial t = cal.run(draw, set_primary, 1.0, affected(draw));
    draw.magnitude = t.m;
    std::string creep = primary(t.fit, clean, creep_channels(draw.creep));
    return {std::move(t), creep};
  }
  // Each part alone to the ratio, then both by a common scale.
  Draw creep_only = draw;
  creep_only.magnitude2 = 0.0;
  const Channels creep_on = creep_channels(draw.creep);
  const Trial c = cal.run(creep_only, set_primary, 1.0, creep_on);
  Draw leak_only = draw;
  leak_only.magnitude = 0.0;
  const Trial l =
      cal.run(leak_only, [](Draw& d, double m) { d.magnitude2 = m; }, 1.0, {true, false});
  const double mc = c.m;
  const double ml = l.m;
  Trial t = cal.run(
      draw,
      [mc, ml](Draw& d, double scale) {
        d.magnitude = mc * scale;
        d.magnitude2 = ml * scale;
      },
      0.75, affected(draw));
  draw.magnitude = mc * t.m;
  draw.magnitude2 = ml * t.m;
  return {std::move(t), primary(c.fit, clean, creep_on)};
}

const char* word(Effect e) {
  switch (e) {
    case Effect::kCreep:
      return "creep";
    case Effect::kLeakage:
      return "charge_leakage";
    case Effect::kStress:
      return "stress_dependence";
    case Effect::kTemperature:
      return "temperature_dependence";
    case Effect::kDynamics:
      return "dynamics";
    case Effect::kDelay:
      return "delay";
    default:
      return "";
  }
}

// The expected names (effect word, judged channel) and every (word, channel) that is not extra.
std::pair<std::vector<Named>, std::vector<Named>> expectations(const Draw& draw,
                                                               const std::string& judged,
                                                               const std::string& creep) {
  std::vector<Named> expected;
  std::vector<Named> allowed;
  const auto allow = [&](const char* w, Channels c) {
    if (c.d) allowed.push_back({w, "D"});
    if (c.s) allowed.push_back({w, "S"});
  };
  switch (draw.effect) {
    case Effect::kNone:
      break;
    case Effect::kCreepLeakage:
      expected = {{"creep", creep}, {"charge_leakage", "D"}};
      allow("creep", creep_channels(draw.creep));
      allow("charge_leakage", {true, false});
      break;
    case Effect::kCreep:
      expected = {{"creep", creep}};
      allow("creep", creep_channels(draw.creep));
      break;
    default:
      expected = {{word(draw.effect), judged}};
      allow(word(draw.effect), affected(draw));
      break;
  }
  return {expected, allowed};
}

bool contains(const std::vector<Named>& list, const Named& n) {
  return std::any_of(list.begin(), list.end(), [&](const Named& x) {
    return x.effect == n.effect && x.channel == n.channel;
  });
}

const ChannelFigures& figures(const Outcome& o, const std::string& channel) {
  return channel == "D" ? o.d : o.s;
}

void judge(Outcome& o, const std::vector<Named>& allowed) {
  if (o.draw.effect == Effect::kNone) {
    o.named_right = o.findings.empty();
    o.extra_names = static_cast<int>(o.findings.size());
    o.excess_ratio = 0.0;
    o.pass = o.findings.empty();
    return;
  }
  o.named_right = std::all_of(o.expected.begin(), o.expected.end(),
                              [&](const Named& e) { return contains(o.findings, e); });
  o.extra_names = static_cast<int>(std::count_if(
      o.findings.begin(), o.findings.end(), [&](const Named& f) { return !contains(allowed, f); }));
  double worst = 0.0;
  for (const Named& e : o.expected) {
    const ChannelFigures& f = figures(o, e.channel);
    const double raised = f.before - f.clean;
    worst = raised > 0.0 ? std::max(worst, (f.after - f.clean) / raised)
                         : std::numeric_limits<double>::quiet_NaN();
    if (std::isnan(worst)) break;
  }
  o.excess_ratio = worst;
  o.pass = o.named_right && o.extra_names <= 1 && worst <= 0.6;
}

std::string names(const std::vector<Named>& list) {
  std::string s;
  for (const Named& n : list) {
    if (!s.empty()) s += ", ";
    s += n.effect + " " + n.channel;
  }
  return s;
}

}  // namespace

Outcome run_draw(std::uint64_t seed, Effect effect) {
  const auto start = std::chrono::steady_clock::now();
  Outcome o;
  o.draw = make_draw(seed, effect);
  const models::Structure structure = structure_for(effect);
  o.structure = std::string(models::to_string(structure));
  Trial trial;
  trial.recording = record(o.draw, {.effect = false});
  trial.fit = fit(trial.recording, structure);
  trial.ratio = 1.0;
  const Fit clean = trial.fit;
  Calibration cal(clean, structure, o.draw.ratio);
  std::string creep = "S";
  if (effect != Effect::kNone) std::tie(trial, creep) = calibrate(o.draw, clean, cal);
  o.ratio_achieved = trial.ratio;
  o.calibration_steps = cal.steps();
  const std::string judged = primary(trial.fit, clean, affected(o.draw));
  const auto [expected, allowed] = expectations(o.draw, judged, creep);
  o.expected = expected;

  const auto diagnosing = std::chrono::steady_clock::now();
  const diagnosis::Result result = diagnosis::diagnose(trial.fit.model, signals(trial.recording));
  o.seconds_diagnose =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - diagnosing).count();
  o.verdict = diagnosis::to_string(result.verdict);
  for (const diagnosis::Finding& f : result.findings) {
    o.findings.push_back({f.effect, f.channel, f.evidence});
  }
  o.improved = std::string(models::to_string(result.improved.structure));
  if (result.improved.vectorial) {
    if (result.improved.sensor) o.improved += ", D plain";
    if (result.improved.actuator) o.improved += ", S plain";
  }

  // The improved model as the runtime runs it against the output each finding was judged on.
  const diagnosis::Outputs rerun = diagnosis::simulate(result.improved, signals(trial.recording));
  for (const diagnosis::ChannelResult& c : result.channels) {
    const std::vector<double>& y = c.channel == "D" ? rerun.sensed : rerun.strain;
    o.model_gap = std::max(o.model_gap, nrmse(c.after, y));
  }

  const Recording val = record(o.draw, {.excitation = 1});
  const Recording val_clean = record(o.draw, {.excitation = 1, .effect = false});
  const diagnosis::Outputs before = diagnosis::simulate(trial.fit.model, signals(val));
  const diagnosis::Outputs after = diagnosis::simulate(result.improved, signals(val));
  const diagnosis::Outputs base = diagnosis::simulate(clean.model, signals(val_clean));
  o.d = {nrmse(val.d, before.sensed), nrmse(val.d, after.sensed), nrmse(val_clean.d, base.sensed)};
  o.s = {nrmse(val.s, before.strain), nrmse(val.s, after.strain), nrmse(val_clean.s, base.strain)};
  judge(o, allowed);
  o.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return o;
}

std::string summary(const Outcome& o) {
  const std::string found = names(o.findings);
  std::array<char, 512> buf{};
  static_cast<void>(std::snprintf(
      buf.data(), buf.size(),
      "%-13s seed %llu | ratio %.2f -> %.2f (%d fits) | %s [%s] right %d extra %d | "
      "validation %% D %.3f/%.3f/%.3f S %.3f/%.3f/%.3f | excess %.2f | %s | %.1f s "
      "(diagnose %.1f s)",
      to_string(o.draw.effect), static_cast<unsigned long long>(o.draw.seed), o.draw.ratio,
      o.ratio_achieved, o.calibration_steps, o.verdict.c_str(), found.c_str(),
      o.named_right ? 1 : 0, o.extra_names, 100 * o.d.before, 100 * o.d.after, 100 * o.d.clean,
      100 * o.s.before, 100 * o.s.after, 100 * o.s.clean, o.excess_ratio, o.pass ? "PASS" : "fail",
      o.seconds, o.seconds_diagnose));
  std::array<char, 64> gap{};
  static_cast<void>(
      std::snprintf(gap.data(), gap.size(), "; runs as judged within %.2g %%)", 100 * o.model_gap));
  return std::string(buf.data()) + "\n    form: " + describe(o.draw) + "; expected [" +
         names(o.expected) + "] (base " + o.structure + "; improved " + o.improved + gap.data();
}

}  // namespace selfsense::independent
