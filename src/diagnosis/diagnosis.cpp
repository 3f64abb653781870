#include "selfsense/diagnosis/diagnosis.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "channel_data.hpp"
#include "held_out.hpp"
#include "reidentified.hpp"
#include "search.hpp"
#include "selfsense/diagnosis/statistics.hpp"
#include "selfsense/models/runtime_model.hpp"
#include "text.hpp"

namespace selfsense::diagnosis {
namespace {

using namespace detail;  // NOLINT(google-build-using-namespace): the diagnosis's own parts

double rms(const std::vector<double>& x) {
  double sum = 0.0;
  for (const double v : x)
    sum += v * v;
  return x.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(x.size()));
}

// Where a residual that no candidate reduces lies: the stretches of large moving RMS, and their
// share of its energy (the whole record when it is spread evenly).
Unexplained unexplained_in(const std::string& channel, const std::vector<double>& residual,
                           double noise) {
  Unexplained u;
  u.channel = channel;
  u.residual_rms = rms(residual);
  u.noise_floor = noise;
  u.where = large_segments(residual, 1.5, 8);
  double total = 0.0;
  for (const double v : residual)
    total += v * v;
  double inside = 0.0;
  for (const Segment& seg : u.where) {
    for (std::size_t k = seg.begin; k < seg.end; ++k)
      inside += residual[k] * residual[k];
  }
  if (u.where.empty() || !(total > 0.0)) {
    u.where = {{0, residual.size()}};
    u.share = 1.0;
  } else {
    u.share = inside / total;
  }
  return u;
}

// What every pass of the diagnosis reads.
struct Context {
  const models::TransducerModel& model;
  const models::TransducerModel& base;  // the model without its corrections
  const Signals& signals;
  const Options& options;
  std::size_t blocks{0};
  bool field{true};
  bool has_sensor{false};
};

// The diagnosis proper, on the base's outputs or, with `stressed`, on the stress-hysteresis
// model that replaced it: each channel's rounds and re-identifications, and the verdict.
Result diagnose_channels(const Context& c, std::vector<ChannelData> channels, Outputs outputs,
                         const std::optional<StressReidentified>& stressed) {
  const models::TransducerModel& model = c.model;
  const Signals& s = c.signals;
  const Options& options = c.options;
  const std::size_t n = s.drive.size();
  const std::size_t blocks = c.blocks;
  const bool field = c.field;
  const bool has_sensor = c.has_sensor;
  Result result;
  result.improved = c.base;
  if (stressed) {
    result.improved = stressed->model;
    outputs = stressed->outputs;
  }
  // The channels hold their own copies; the electrostriction term reads the sensed channel's
  // response to the drive alone (D - d T: the polarization and the dielectric part).
  static_cast<void>(hold_finite(outputs.sensed));
  // A channel whose side the stress-hysteresis structure took (a kept one runs as without it).
  const auto replaced = [&](const ChannelData& ch) {
    return stressed && stressed->replaces(ch.name);
  };
  const bool sensed_replaced =
      std::any_of(channels.begin(), channels.end(),
                  [&](const ChannelData& ch) { return ch.sensed && replaced(ch); });
  const std::vector<double> sensed_response = response_to_drive(
      outputs.sensed, sensed_replaced ? 0.0 : coupling_of(model.sensor), s.stress);

  const std::vector<Segment> drive_holds = holds_of(s.drive);
  for (ChannelData& ch : channels) {
    const Rows rows = make_rows(hold_finite(ch.base), blocks);
    ch.sensed_model = sensed_response;
    const std::vector<double> model_output = ch.base;  // for the figures before
    std::vector<Finding> stress_found;
    const bool stress_side = replaced(ch);
    if (stress_side) {
      ch.base = ch.sensed ? outputs.sensed : outputs.strain;
      static_cast<void>(hold_finite(ch.base));
      ch.coupling = 0.0;
      ch.affine = false;
      ch.loop_reidentified = true;
      for (const Finding& f : stressed->named) {
        if (f.channel == ch.name) stress_found.push_back(f);
      }
    }
    // The rounds on one base output of the channel, with an effect found by re-identification
    // (reidentified.hpp) accepted first when given.
    const auto search = [&](const std::optional<Reidentified>& reid, std::vector<Finding>& found) {
      if (reid) ch.base = reid->base;
      identification::CorrectionSignals cs;
      cs.y = ch.base;
      cs.recorded = ch.recorded;
      cs.drive = s.drive;
      cs.stress = s.stress;
      cs.temperature = s.temperature;
      cs.sensed = has_sensor ? std::span<const double>(sensed_response) : std::span<const double>();
      // A re-identified side has its own coupling, which its terms were fitted with.
      const std::vector<double> response =
          response_to_drive(ch.base, reid ? coupling_of(reid->side) : ch.coupling, s.stress);
      cs.response = response;
      cs.sample_time = s.sample_time;
      if (!s.temperature.empty()) cs.temperature_reference_degc = s.temperature[0];
      SearchState st;
      st.current = ch.base;
      st.original_sse = sse_over(ch.recorded, model_output, rows.judge);
      if (reid) {
        st.accepted = reid->correction;
        st.accepted_terms = reid->terms;
        st.used.push_back(reid->candidate);
        st.current = reid->output;
        found.push_back(reid->finding);
      }
      st.current_sse = sse_over(ch.recorded, st.current, rows.judge);
      const SearchInput in{ch, cs, s, rows, drive_holds, has_sensor, !field, options};
      search_rounds(in, st, found);
      local_pass(in, st, found);
      absorbed_pass(in, st, found);
      return st;
    };
    const auto accept_side = [&](const Reidentified& reid) {
      (ch.sensed ? result.improved.sensor : result.improved.actuator) = reid.side;
      // A plain side kept beside the stress-hysteresis structure: the model keeps its structure.
      if (reid.structure && !result.improved.vectorial) result.improved.structure = *reid.structure;
    };
    // A stack that warmed bends a base identified on it (its creep and loop follow the drift):
    // where the temperature moved, the channel's side is re-identified with the temperature's
    // terms, and if that forecasts better the rounds run on it.
    const std::optional<Reidentified> warmed =
        stress_side ? std::nullopt : reidentified_temperature(model, s, ch, model_output, options);
    if (warmed) accept_side(*warmed);
    std::vector<Finding> found;
    SearchState st = search(warmed, found);
    found.insert(found.begin(), stress_found.begin(), stress_found.end());
    bool reidentified = warmed.has_value() || stress_side;
    // The rounds again on a re-identified side; `kept` goes before what they find.
    const auto search_again = [&](const Reidentified& reid, std::vector<Finding> kept) {
      std::vector<Finding> again;
      st = search(reid, again);
      kept.insert(kept.end(), std::make_move_iterator(again.begin()),
                  std::make_move_iterator(again.end()));
      found = std::move(kept);
      accept_side(reid);
      reidentified = true;
    };
    const auto named_only = [&](std::string_view effect) {
      return std::all_of(found.begin(), found.end(),
                         [&](const Finding& f) { return f.effect == effect; });
    };
    // A loop identified on a creeping stack bends to the creep, and one identified with a leak
    // bends its operators to the leak: on a model without creep operators, where the rounds name
    // nothing on the channel but creep and the loop's shape (a loop bent to the creep shows as
    // a change of its shape too), the structure with them is judged by re-identification,
    // and on the sensed channel the leak too (also where nothing is named on a re-identified
    // side). Over one record a slow lag integrates like a leak, so each imitates the other. The
    // leak goes first where the creep does not hold or the leak does better on both halves (the
    // identification's and the forecast's); where they split, the richer structure goes first
    // (the disc's holds: the creep fits its half 99.8 % better and forecasts 66 %, the leak 33 %
    // and 79 %; on its validation block the creep structure is 6 %, the leak 14 %). The other is
    // then judged beside the first.
    const bool creep_or_loop_shape = std::all_of(found.begin(), found.end(), [](const Finding& f) {
      return f.effect == "creep" || f.effect == "hysteresis" || f.effect == "asymmetric_hysteresis";
    });
    const bool creep_candidate =
        !reidentified && model.structure == models::Structure::kHysteresis && creep_or_loop_shape;
    // On a model with creep operators the rounds' creep terms on D take a slow leak for creep
    // (its drift over the record is a slow lag's; the base's own lags took in the rest), so a
    // channel where they name nothing but creep is judged for a leak too (the creep terms are
    // not re-identified there: the model has its creep operators already).
    const bool only_creep = !found.empty() && named_only("creep");
    const bool leak_candidate = ch.sensed && !stress_side &&
                                (found.empty() || creep_candidate || (!reidentified && only_creep));
    std::optional<Reidentified> creep =
        creep_candidate ? reidentified_creep(model, s, ch, model_output, options) : std::nullopt;
    std::optional<Reidentified> leak =
        leak_candidate ? reidentified_leak(model, s, ch, model_output, options) : std::nullopt;
    const bool leak_dominates =
        leak && (!creep || (leak->fit_explains >= creep->fit_explains &&
                            leak->finding.explains > creep->finding.explains));
    if (creep && !leak_dominates) {
      const Finding creep_found = creep->finding;
      search_again(*creep, {});
      // The leak beside the creep: judged with the creep's structure, where the rounds on it
      // name nothing but creep, by its forecast alone (the structure's slowest lags take a slow
      // leak in over the half they are fitted on; reidentified.hpp, ShownBy).
      if (leak_candidate && named_only("creep")) {
        models::TransducerModel with_creep = model;
        with_creep.structure = *creep->structure;
        std::optional<Reidentified> beside =
            reidentified_leak(with_creep, s, ch, model_output, options, ShownBy::kForecast);
        if (beside) search_again(*beside, {creep_found});
      }
    } else if (leak) {
      const Finding leak_found = leak->finding;
      search_again(*leak, {});
      // Creep beside the leak: both structures identified with the leak undone.
      std::optional<Reidentified> beside =
          creep_candidate
              ? reidentified_creep(model, s, ch, model_output, options, leak->correction)
              : std::nullopt;
      if (beside) {
        beside->candidate = leak->candidate;
        beside->terms = leak->terms;
        search_again(*beside, {leak_found});
      }
    }
    // Neither alone: the pair as one forecast (reidentified.hpp, CreepAndLeak).
    if (creep_candidate && leak_candidate && !creep && !leak) {
      const std::optional<CreepAndLeak> pair =
          reidentified_creep_and_leak(model, s, ch, model_output, options);
      if (pair) search_again(pair->reidentified, {pair->leak});
    }
    // A moving load bends a base identified under it the same way (its loop follows the
    // stress): where the rounds named the stress dependence on a side nothing re-identified, or
    // named nothing while a stress candidate led their first round, the side is re-identified
    // with the stress's terms undone, as for the temperature. (A base bent far enough leaves
    // the terms after it no block test to win: 3800037's coupling, 10-30 % of the stroke over
    // the load, explained 30 % of S's held-out residual with one block 1.9x worse.)
    const bool named_stress = std::any_of(found.begin(), found.end(), [](const Finding& f) {
      return f.effect == "stress_dependence";
    });
    if (!reidentified && (named_stress || (found.empty() && st.stress_leads))) {
      std::optional<Reidentified> loaded =
          reidentified_stress_terms(model, s, ch, model_output, options);
      if (loaded) {
        // Its loop was identified on this record with the terms: what loop shape is left is
        // the structure's own class (as on the stress-hysteresis structure).
        ch.loop_reidentified = true;
        search_again(*loaded, {});
      }
    }
    // A channel sampled late bends the base the same way (its fastest lags follow the lag, so a
    // delay fitted after it wins on fast blocks and loses on slow ones; a lag of several
    // samples it takes in as loop width, and a delay after it then explains next to nothing):
    // where nothing but lags is named on the channel, the delay (on S also a mode around the
    // rounds' one) is judged by re-identification (more cheaply where the rounds saw no lag).
    const bool only_lags = std::all_of(found.begin(), found.end(), [](const Finding& f) {
      return f.effect == "delay" || f.effect == "dynamics";
    });
    if (!reidentified && (st.rounds_named == 0 || only_lags)) {
      const LagSeen seen =
          st.lag_explains >= options.min_explains ? LagSeen::kInRounds : LagSeen::kNo;
      // A delay the rounds named alone: the side identified with it undone carries it where it
      // fits the record better than the delay after the model (the same class and parameter
      // count: the side fitted with the delay jointly against the side fitted without it and the
      // delay after; the rounds' held-out test has named it already). A mode named alone (by
      // the rounds or in one stretch): the delay carried in its place where it is the simpler
      // form of the lag on both halves (reidentified.hpp) and the side identified with it fits
      // the record better than the mode after the model, which has a parameter more, and no
      // worse where the mode was named (the stretches that showed it). A delay cannot ring: the
      // 1 Hz set's ringing after its step, named in its stretch, was otherwise replaced by a
      // carried delay that fits the judged rows 1 % better than the model's own output.
      const bool one_lag = found.size() == 1 &&
                           (found.front().effect == "delay" || found.front().effect == "dynamics");
      const Finding* named_lag = one_lag ? &found.front() : nullptr;
      std::optional<Reidentified> late = reidentified_lag(
          model, s, ch, model_output, options, st.lag_mode, seen, st.named_modes, named_lag);
      if (late && late->carried && named_lag != nullptr) {
        const double carried_sse = sse_over(ch.recorded, late->output, rows.judge);
        const bool was_delay = named_lag->effect == "delay";
        const auto where_named_sse = [&](const std::vector<double>& output) {
          double sse = 0.0;
          for (const Segment& w : named_lag->where)
            sse += segment_sse(ch.recorded, output, w);
          return sse;
        };
        const bool fits_better = carried_sse < st.current_sse;
        if (was_delay && fits_better) {
          late->finding.evidence += format(
              "; carried by the model's side identified again with a delay of %.3g samples "
              "undone, which fits the record %.0f %% better than the delay after the model (the "
              "side had taken part of the delay in)",
              late->correction.delay_s / s.sample_time,
              100.0 * (1.0 - carried_sse / st.current_sse));
        } else if (!was_delay && fits_better &&
                   where_named_sse(late->output) <= where_named_sse(st.current)) {
          // In the mode's place: a finding of its own, its share of the residual on the judged
          // rows (which the side saw when identified on the whole record, as a carried delay's;
          // the contract's share for a finding of the rounds is held out).
          late->finding.explains =
              st.original_sse > 0.0 ? std::max(0.0, 1.0 - carried_sse / st.original_sse) : 0.0;
          const std::string judged = late->finding.evidence;
          describe(late->finding, *late->candidate, late->correction, ch, s, model_output,
                   late->output,
                   judged + format("; the model's side identified again with it undone fits the "
                                   "record %.0f %% better than the mode after the model",
                                   100.0 * (1.0 - carried_sse / st.current_sse)));
        } else {
          // The rounds' finding and model stand; for a delay the finding says what was weighed.
          if (was_delay) {
            found.front().evidence += format(
                "; the model's side identified again with the delay undone fitted the record "
                "%.0f %% worse than the delay after the model, which stands",
                100.0 * (carried_sse / st.current_sse - 1.0));
          }
          late.reset();
        }
      }
      if (late) search_again(*late, {});
    }
    result.findings.insert(result.findings.end(), std::make_move_iterator(found.begin()),
                           std::make_move_iterator(found.end()));

    ChannelResult out;
    out.channel = ch.name;
    out.recorded.assign(ch.recorded.begin(), ch.recorded.end());
    out.before = model_output;
    out.after = st.current;
    std::vector<double> residual(n);
    std::vector<double> residual_after(n);
    for (std::size_t k = 0; k < n; ++k) {
      residual[k] = ch.recorded[k] - model_output[k];
      residual_after[k] = ch.recorded[k] - st.current[k];
    }
    out.located = large_segments(residual, 1.5, 8);
    out.noise_floor = noise_floor(residual);
    out.residual_rms = rms(residual_after);
    const bool named = std::any_of(result.findings.begin(), result.findings.end(),
                                   [&](const Finding& f) { return f.channel == ch.name; });
    if (!named && out.residual_rms > options.unexplained_ratio * out.noise_floor) {
      result.unexplained.push_back(unexplained_in(ch.name, residual_after, out.noise_floor));
    }
    out.test_before = correlation_test(residual, s.drive);
    out.test_after = correlation_test(residual_after, s.drive);
    result.channels.push_back(std::move(out));
    if (!st.accepted.empty()) {
      (ch.sensed ? result.improved.sensed_correction : result.improved.strain_correction) =
          st.accepted;
    }
  }
  result.mismatch = !result.findings.empty();
  if (result.mismatch) {
    result.verdict = Verdict::kMismatch;
  } else if (!result.unexplained.empty()) {
    result.verdict = Verdict::kUnexplained;
  }
  return result;
}

}  // namespace

const char* to_string(Verdict v) noexcept {
  switch (v) {
    case Verdict::kMismatch:
      return "mismatch";
    case Verdict::kUnexplained:
      return "unexplained";
    case Verdict::kConsistent:
      break;
  }
  return "consistent";
}

Outputs simulate(const models::TransducerModel& model, const Signals& s) {
  models::Simulation sim(model, models::RuntimeOptions{s.sample_time});
  Outputs out;
  const std::size_t n = s.drive.size();
  out.sensed.resize(n);
  out.strain.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    if (!s.temperature.empty()) sim.set_temperature(s.temperature[k]);
    const models::Simulation::Output o = sim.step(s.drive[k], s.stress.empty() ? 0.0 : s.stress[k]);
    out.sensed[k] = o.sensed;
    out.strain[k] = o.strain;
  }
  return out;
}

Result diagnose(const models::TransducerModel& model, const Signals& s, const Options& options) {
  const std::size_t n = s.drive.size();
  const auto sized = [n](std::span<const double> x) { return x.empty() || x.size() == n; };
  if (n < 100 || !sized(s.sensed) || !sized(s.strain) || !sized(s.stress) ||
      !sized(s.temperature) || !(s.sample_time > 0.0)) {
    throw std::invalid_argument(
        "diagnose: needs at least 100 samples of the drive, channels of equal length and a "
        "sample time");
  }
  // Half the blocks judge; the signed-rank test reaches p <= 0.01 from 7 of them.
  if (options.blocks < 14) {
    throw std::invalid_argument("diagnose: Options.blocks: " + std::to_string(options.blocks) +
                                " leaves fewer than 7 held-out blocks; nothing could be named");
  }
  models::TransducerModel base = model;
  base.sensed_correction.reset();
  base.strain_correction.reset();
  Outputs outputs = simulate(base, s);
  const bool field = model.drive() == models::Drive::kField;
  const bool has_sensor = model.sensor || (model.vectorial && model.vectorial->sensor);
  const bool has_actuator = model.actuator || (model.vectorial && model.vectorial->actuator);

  std::vector<ChannelData> channels;
  if (has_sensor && !s.sensed.empty()) {
    channels.push_back({field ? "D" : "E",
                        true,
                        s.sensed,
                        outputs.sensed,
                        coupling_of(model.sensor),
                        {},
                        !model.vectorial.has_value()});
  }
  if (has_actuator && !s.strain.empty()) {
    channels.push_back({"S", false, s.strain, outputs.strain, coupling_of(model.actuator)});
  }
  if (channels.empty()) {
    throw std::invalid_argument(
        "diagnose: the recording references none of the model's outputs (D or S)");
  }

  const std::size_t blocks = std::max<std::size_t>(2, options.blocks);
  const Context context{model, base, s, options, blocks, field, has_sensor};
  Result first = diagnose_channels(context, channels, outputs, std::nullopt);
  // A generic loop correction is part of what the structure below re-identifies (its loop).
  const auto stress_or_loop = [](const Finding& f) {
    return f.effect == "stress_dependence" ||
           std::any_of(candidates().begin(), candidates().end(),
                       [&](const Candidate& c) { return c.generic && f.effect == c.effect; });
  };
  if (!std::all_of(first.findings.begin(), first.findings.end(), stress_or_loop)) return first;
  // A loop and coupling that move with the stress bend an affine base: where nothing but the
  // stress (or the loop's generic shape beside it) is named, judged for the whole model (it
  // replaces every side it does not forecast worse) by re-identification with the
  // stress-hysteresis structure (the corrections carry a coupling's change, not a loop that
  // moves with T); then each channel's rounds run on it and no side is re-identified again.
  const std::optional<StressReidentified> stressed =
      reidentified_stress(model, s, channels, options);
  if (!stressed) return first;
  // Taken where it names a channel the corrections did not, or explains more of a channel they
  // named: its share is of forecasts a half ahead, theirs of interleaved held-out blocks, so a
  // larger share of the harsher test is the better model of that channel.
  const bool better =
      std::any_of(stressed->named.begin(), stressed->named.end(), [&](const Finding& f) {
        double corrected = 0.0;  // the findings' shares of one channel add up
        for (const Finding& g : first.findings) {
          if (g.channel == f.channel) corrected += g.explains;
        }
        return f.explains > corrected;
      });
  return better ? diagnose_channels(context, channels, outputs, stressed) : first;
}

}  // namespace selfsense::diagnosis
