#include "reidentified.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "candidates.hpp"
#include "held_out.hpp"
#include "selfsense/diagnosis/mode_undone.hpp"
#include "selfsense/diagnosis/read_later.hpp"
#include "selfsense/identification/transducer_fit.hpp"
#include "text.hpp"

namespace selfsense::diagnosis::detail {
namespace {

// An effect after the model, and what it costs to judge: the channel's side identified on the
// channel with the effect undone.
struct Trial {
  models::ChannelCorrection effect{};
  std::vector<double> forecast{};  // the identified model's channel through the effect
  double first_half_sse{std::numeric_limits<double>::infinity()};
  std::vector<double> start{};  // the identified side's remanent state at the first sample
};

class Judge {
 public:
  Judge(const models::TransducerModel& model, const Signals& s, const ChannelData& ch)
      : Judge(s, ch, model.structure) {}
  // Identifies with another structure than the model's (the model's with creep operators).
  Judge(const Signals& s, const ChannelData& ch, models::Structure structure)
      : s_(s), ch_(ch), structure_(structure), half_(s.drive.size() / 2) {}

  [[nodiscard]] std::size_t half() const { return half_; }

  // The channel as the model would see it without the effect: a delay is undone by reading
  // the record that much later (read_later), a mode by its offline inverse (mode_undone.hpp), a
  // leak by the correction stage's inverse.
  [[nodiscard]] std::vector<double> undone(const models::ChannelCorrection& effect) const {
    const std::span<const double> x = ch_.recorded;
    if (effect.dynamics_frequency_hz > 0.0) {
      return modes_undone(x, effect, s_.sample_time);
    }
    if (effect.delay_s > 0.0) return read_later(x, effect.delay_s / s_.sample_time);
    std::vector<double> out(x.begin(), x.end());
    if (effect.empty()) return out;
    models::CorrectionStage stage(effect, s_.sample_time);
    for (std::size_t k = 0; k < out.size(); ++k) {
      models::CorrectionStage::Inputs in;
      in.drive = s_.drive[k];
      out[k] = stage.invert(x[k], in);
    }
    return out;
  }

  // The structure's side of this channel identified on `y` over its first `samples` samples,
  // from `start` when given (OperatorStructure::start), else from the state it searches for.
  [[nodiscard]] models::TransducerModel identify(const std::vector<double>& y, std::size_t samples,
                                                 const std::vector<double>& start = {}) const {
    return identify_over(y, 0, samples, start);
  }

  // The identified model's channel over the whole record, through the effect.
  [[nodiscard]] std::vector<double> forecast(const models::TransducerModel& m,
                                             const models::ChannelCorrection& effect) const {
    const Outputs o = simulate(m, s_);
    std::vector<double> y = ch_.sensed ? o.sensed : o.strain;
    static_cast<void>(hold_finite(y));
    if (effect.empty()) return y;
    identification::CorrectionSignals cs;
    cs.y = y;
    cs.drive = s_.drive;
    cs.sample_time = s_.sample_time;
    return identification::apply_correction(cs, effect);
  }

  // The side identified on the first half with `effect` undone, from `start` when given. The
  // trials of one family take their null's start (Trial::start): the drive left the stack in
  // the same state whichever effect is undone, and on a long record the search for that state
  // costs most of an identification (five sixths at 1e6 samples: docs/diagnose.md, "Speed").
  [[nodiscard]] Trial trial(const models::ChannelCorrection& effect,
                            const std::vector<double>& start = {}) const {
    Trial t;
    t.effect = effect;
    try {
      const models::TransducerModel m = effect.empty() && start.empty()
                                            ? first_half_fit(structure_, s_, ch_)
                                            : identify(undone(effect), half_, start);
      if (const std::optional<models::SideModel>& side = side_of(m)) t.start = side->history;
      t.forecast = forecast(m, effect);
    } catch (const std::invalid_argument&) {
      return t;  // no identification with this effect undone: not a candidate
    }
    double sse = 0.0;
    for (std::size_t k = 0; k < half_; ++k) {
      const double e = ch_.recorded[k] - t.forecast[k];
      sse += e * e;
    }
    if (std::isfinite(sse)) t.first_half_sse = sse;
    return t;
  }

  // The effect the other way round: the side identified on the second half with the effect
  // undone, the whole record through the effect (empty where no identification exists). Its
  // first half is a backcast.
  [[nodiscard]] std::vector<double> backcast(const models::ChannelCorrection& effect) const {
    try {
      const std::vector<double> y = undone(effect);
      return forecast(identify_over(y, half_, y.size() - half_), effect);
    } catch (const std::invalid_argument&) {
      return {};
    }
  }

  [[nodiscard]] const std::optional<models::SideModel>& side_of(
      const models::TransducerModel& m) const {
    return ch_.sensed ? m.sensor : m.actuator;
  }

 private:
  // The structure's side identified on `count` samples of `y` from `offset` (the model's state
  // starts at rest there, as at the start of any recording).
  [[nodiscard]] models::TransducerModel identify_over(const std::vector<double>& y,
                                                      std::size_t offset, std::size_t count,
                                                      const std::vector<double>& start = {}) const {
    const auto part = [offset, count](std::span<const double> x) {
      return x.empty() ? x : x.subspan(offset, count);
    };
    identification::TransducerSignals t;
    t.drive = part(s_.drive);
    (ch_.sensed ? t.sensed : t.strain) = part(y);
    t.stress = part(s_.stress);
    t.sample_time = s_.sample_time;
    identification::IdentificationOptions options = reidentification_options(structure_);
    options.start = start;
    return identification::identify(t, structure_, options);
  }

  const Signals& s_;
  const ChannelData& ch_;
  models::Structure structure_;
  std::size_t half_;
};

// The leaks tried: the charge amplifier's high-pass from a third of the record to a hundred
// records, the conductance's integral from 0.1 % to 10 % of D's range over the record, either
// sign; then the best one's neighbours at a factor sqrt(3).
std::vector<models::ChannelCorrection> coarse_leaks(const Signals& s) {
  std::vector<models::ChannelCorrection> out;
  const double duration = static_cast<double>(s.drive.size()) * s.sample_time;
  for (const double records : {0.3, 1.0, 3.0, 10.0, 30.0, 100.0}) {
    models::ChannelCorrection c;
    c.leakage_tau_s = records * duration;
    out.push_back(c);
  }
  double q = 0.0;
  double q_lo = 0.0;
  double q_hi = 0.0;
  for (std::size_t k = 1; k < s.drive.size(); ++k) {
    q += s.sample_time * s.drive[k];
    q_lo = std::min(q_lo, q);
    q_hi = std::max(q_hi, q);
  }
  const double d_range = range_of(s.sensed);
  if (!(q_hi - q_lo > 0.0) || !(d_range > 0.0)) return out;
  for (const double share : {0.001, 0.003, 0.01, 0.03, 0.1}) {
    for (const double sign : {1.0, -1.0}) {
      models::ChannelCorrection c;
      c.drive_integral_per_s = sign * share * d_range / (q_hi - q_lo);
      out.push_back(c);
    }
  }
  return out;
}

models::ChannelCorrection scaled(models::ChannelCorrection c, double factor) {
  c.leakage_tau_s *= factor;
  c.drive_integral_per_s *= factor;
  return c;
}

// A leak's neighbours: at a factor sqrt(3) either way.
std::vector<models::ChannelCorrection> leak_neighbours(const models::ChannelCorrection& c) {
  return {scaled(c, std::sqrt(3.0)), scaled(c, 1.0 / std::sqrt(3.0))};
}

}  // namespace

models::TransducerModel first_half_fit(models::Structure structure, const Signals& s,
                                       const ChannelData& ch) {
  if (const models::TransducerModel* kept = ch.first_half->find(structure)) return *kept;
  const Judge judge(s, ch, structure);
  models::TransducerModel m = judge.identify(judge.undone({}), judge.half());
  ch.first_half->keep(structure, m);
  return m;
}

identification::IdentificationOptions reidentification_options(models::Structure structure) {
  identification::IdentificationOptions options = identification::defaults_for(structure);
  options.max_rows = kReidentifiedRows;
  return options;
}

const Candidate& candidate_using(CorrectionTerm term) {
  for (const Candidate& c : candidates()) {
    if (uses_term(c, term)) return c;
  }
  throw std::logic_error("reidentified: no candidate carries the term");
}

namespace {

// Rows that judge [begin, end) in `judging` blocks and fit the rest.
Rows held_rows(std::size_t n, std::size_t begin, std::size_t end, std::size_t judging,
               const std::vector<double>& a, const std::vector<double>& b) {
  Rows r;
  r.blocks = 2 * judging;
  r.fit.assign(n, false);
  r.judge.assign(n, false);
  r.block.assign(n, 0);
  for (std::size_t k = 0; k < n; ++k) {
    const bool finite = std::isfinite(a[k]) && std::isfinite(b[k]);
    if (k < begin || k >= end) {
      r.fit[k] = finite;
      continue;
    }
    r.judge[k] = finite;
    r.block[k] = 2 * std::min(judging - 1, (k - begin) * judging / (end - begin)) + 1;
  }
  return r;
}

}  // namespace

Rows forecast_rows(std::size_t n, std::size_t half, std::size_t judging,
                   const std::vector<double>& a, const std::vector<double>& b) {
  return held_rows(n, half, n, judging, a, b);
}

Rows backcast_rows(std::size_t n, std::size_t half, std::size_t judging,
                   const std::vector<double>& a, const std::vector<double>& b) {
  return held_rows(n, 0, half, judging, a, b);
}

std::vector<Segment> where_it_changes(const std::vector<double>& output,
                                      const std::vector<double>& current) {
  std::vector<double> change(output.size());
  for (std::size_t k = 0; k < output.size(); ++k)
    change[k] = output[k] - current[k];
  std::vector<Segment> where = large_segments(change, 1.5, 5);
  if (where.empty()) where = {{0, output.size()}};
  return where;
}

namespace {

// The forecast's judgement of `best` against `null` (both identified on the first half): it
// must (with ShownBy::kFitAndForecast) fit that half by min_explains better (the
// identification's own evidence: on clean stacks a small effect mends the forecast of a model of
// another class a little; it does not change the fit) and beat the null on the second half by
// the rules of a round. The share of the null's error it removes there, or nullopt.
std::optional<double> forecast_explains(const Trial& null, const Trial& best, const ChannelData& ch,
                                        std::size_t half, const Options& options,
                                        ShownBy evidence) {
  if (null.forecast.empty() || best.forecast.empty() ||
      (evidence == ShownBy::kFitAndForecast &&
       1.0 - best.first_half_sse / null.first_half_sse < options.min_explains)) {
    return std::nullopt;
  }
  const Rows rows =
      forecast_rows(ch.recorded.size(), half, options.blocks, null.forecast, best.forecast);
  const double null_sse = sse_over(ch.recorded, null.forecast, rows.judge);
  const double best_sse = sse_over(ch.recorded, best.forecast, rows.judge);
  if (!(null_sse > 0.0)) return std::nullopt;
  const double explains = 1.0 - best_sse / null_sse;
  if (explains < options.min_explains ||
      !passes_blocks(block_explains(ch.recorded, null.forecast, best.forecast, rows), options)) {
    return std::nullopt;
  }
  return explains;
}

// `a` forecasts the second half no worse than `b` (over the rows where both are finite).
bool forecasts_no_worse(const Judge& judge, const ChannelData& ch, const Trial& a, const Trial& b,
                        const Options& options) {
  const Rows rows =
      forecast_rows(ch.recorded.size(), judge.half(), options.blocks, a.forecast, b.forecast);
  return sse_over(ch.recorded, a.forecast, rows.judge) <=
         sse_over(ch.recorded, b.forecast, rows.judge);
}

// The improved side: identified on the whole record with the effect undone.
std::optional<Reidentified> identified_whole(const Judge& judge,
                                             const models::ChannelCorrection& effect,
                                             const ChannelData& ch, double explains) {
  Reidentified r;
  r.correction = effect;
  try {
    const models::TransducerModel whole = judge.identify(judge.undone(effect), ch.recorded.size());
    const std::optional<models::SideModel>& side = judge.side_of(whole);
    if (!side) return std::nullopt;
    r.side = *side;
    r.base = judge.forecast(whole, models::ChannelCorrection{});
    r.output = judge.forecast(whole, effect);
  } catch (const std::invalid_argument&) {
    return std::nullopt;
  }
  r.finding.channel = ch.name;
  r.finding.explains = explains;
  return r;
}

// A family's winner identified in full, from the start its own search picks. The null's start
// chooses among the family cheaply; the winner's own start decides how it fits and forecasts
// where it is compared and judged (a mode undone reshapes the response of the first sweep,
// where the start is read: the 1 Hz set's ringing lost to a delay from the null's start).
Trial in_full(const Judge& judge, Trial best) {
  if (best.forecast.empty()) return best;
  Trial full = judge.trial(best.effect);
  return full.forecast.empty() ? best : full;
}

// The effect of one family that fits the first half best: a coarse grid, then `refine`'s
// neighbours of the best, each trial from `start` (the null's); the winner then in full.
template <typename Refine>
Trial best_of(const Judge& judge, const std::vector<models::ChannelCorrection>& grid,
              Refine&& refine, const std::vector<double>& start) {
  Trial best;
  for (const models::ChannelCorrection& effect : grid) {
    Trial t = judge.trial(effect, start);
    if (t.first_half_sse < best.first_half_sse) best = std::move(t);
  }
  if (best.forecast.empty()) return best;
  for (const models::ChannelCorrection& effect : refine(best.effect)) {
    Trial t = judge.trial(effect, start);
    if (t.first_half_sse < best.first_half_sse) best = std::move(t);
  }
  return in_full(judge, std::move(best));
}

// The effect's backcast against the null's by the rules of a round: each side identified on
// the second half by its judge (backcast_rows).
bool shown_backwards(const Judge& null_judge, const models::ChannelCorrection& null_effect,
                     const Judge& judge, const models::ChannelCorrection& effect,
                     const ChannelData& ch, const Options& options) {
  const std::vector<double> null = null_judge.backcast(null_effect);
  const std::vector<double> with = judge.backcast(effect);
  if (null.empty() || with.empty()) return false;
  const Rows rows = backcast_rows(ch.recorded.size(), judge.half(), options.blocks, null, with);
  const double null_sse = sse_over(ch.recorded, null, rows.judge);
  if (!(null_sse > 0.0)) return false;
  return 1.0 - sse_over(ch.recorded, with, rows.judge) / null_sse >= options.min_explains &&
         passes_blocks(block_explains(ch.recorded, null, with, rows), options);
}

// forecast_explains, and where kFitAndForecast's fit falls short, the forecast with the
// backcast: a base identified with the effect took part of it in over the half it was fitted on
// (a sub-sample delay into its fastest lags, a slow leak into its slowest), so the fit cannot
// show it; held-out data both ways can (reidentified.hpp, ShownBy). `null` is null_judge's.
std::optional<double> held_out_explains(const Judge& null_judge, const Trial& null,
                                        const Judge& judge, const Trial& best,
                                        const ChannelData& ch, const Options& options,
                                        ShownBy evidence) {
  std::optional<double> explains =
      forecast_explains(null, best, ch, judge.half(), options, evidence);
  if (explains || evidence != ShownBy::kFitAndForecast) return explains;
  explains = forecast_explains(null, best, ch, judge.half(), options, ShownBy::kForecast);
  if (explains && !shown_backwards(null_judge, null.effect, judge, best.effect, ch, options)) {
    explains.reset();
  }
  return explains;
}

// `best` judged against `null` by held_out_explains; the side re-identified on the whole record
// with it.
std::optional<Reidentified> judged(const Judge& judge, const ChannelData& ch, const Trial& null,
                                   const Trial& best, const Options& options, ShownBy evidence) {
  const std::optional<double> explains =
      held_out_explains(judge, null, judge, best, ch, options, evidence);
  if (!explains) return std::nullopt;
  std::optional<Reidentified> r = identified_whole(judge, best.effect, ch, *explains);
  if (r) r->fit_explains = 1.0 - best.first_half_sse / null.first_half_sse;
  return r;
}

// One family of effects judged as a forecast: the effect chosen on the first half's fit
// (best_of), judged by forecast_explains.
template <typename Refine>
std::optional<Reidentified> judged_as_forecast(const Judge& judge, const ChannelData& ch,
                                               const std::vector<models::ChannelCorrection>& grid,
                                               Refine&& refine, const Options& options,
                                               ShownBy evidence = ShownBy::kFitAndForecast) {
  const Trial null = judge.trial(models::ChannelCorrection{});
  if (null.forecast.empty()) return std::nullopt;
  const Trial best = best_of(judge, grid, std::forward<Refine>(refine), null.start);
  if (best.forecast.empty()) return std::nullopt;
  return judged(judge, ch, null, best, options, evidence);
}

// The model and recording allow a side to be re-identified on this channel.
bool reidentifiable(const models::TransducerModel& model, const Signals& s, const ChannelData& ch) {
  const std::size_t n = s.drive.size();
  const bool has_side = ch.sensed ? model.sensor.has_value() : model.actuator.has_value();
  if (model.drive() != models::Drive::kField || model.vectorial || !has_side ||
      ch.recorded.size() != n || n < 1000) {
    return false;
  }
  // Without T the re-identified side would lose the model's stress coupling.
  return ch.coupling == 0.0 || !s.stress.empty();
}

std::string as_forecast(const Judge& judge, const Signals& s, const ChannelData& ch,
                        const std::string& effect) {
  return format(
             "on the last %.3g s of the recording as a forecast (the model's structure "
             "identified on the first half with the ",
             static_cast<double>(s.drive.size() - judge.half()) * s.sample_time) +
         effect + " undone, against the same structure identified on " + ch.name +
         " as recorded: the model had bent its own operators to the " + effect + ")";
}

// The creep operators' time constants, for the evidence: "lags of 0.01-100 s".
std::string lags_of(const models::SideModel& side) {
  const std::vector<double>& lambda = side.op.creep.eigenvalues;
  if (lambda.empty()) return "no lags";
  const auto [lo, hi] = std::minmax_element(lambda.begin(), lambda.end());
  return format("%.0f lags of ", static_cast<double>(lambda.size())) + format("%.2g-", 1.0 / *hi) +
         format("%.2g s", 1.0 / *lo);
}

constexpr models::Structure kWithCreep = models::Structure::kHysteresisCreep;

// The leak of the grid (coarse_leaks, then the best one's neighbours at a factor sqrt(3)) that
// fits the first half best with this judge's structure, each trial from `start`.
Trial best_leak(const Judge& judge, const Signals& s, const std::vector<double>& start) {
  return best_of(judge, coarse_leaks(s), leak_neighbours, start);
}

// The leak's candidate, terms and finding on a re-identified side that carries it.
void as_leak(Reidentified& r, const ChannelData& ch, const Signals& s,
             const std::vector<double>& current, const std::string& judged) {
  const models::ChannelCorrection& leak = r.correction;
  const CorrectionTerm term =
      leak.leakage_tau_s > 0.0 ? CorrectionTerm::kLeakage : CorrectionTerm::kDriveIntegral;
  r.candidate = &candidate_using(term);
  r.terms = {term};
  r.finding.effect = "charge_leakage";
  r.finding.where = where_it_changes(r.output, current);
  describe(r.finding, *r.candidate, leak, ch, s, current, r.output, judged);
}

// The creep finding of a side re-identified with creep operators.
void as_creep(Reidentified& r, const ChannelData& ch, const Signals& s,
              const std::vector<double>& current, std::size_t half) {
  r.structure = kWithCreep;
  r.candidate = &candidate_using(CorrectionTerm::kCreep);
  Finding& f = r.finding;
  f.effect = r.candidate->effect;
  f.where = where_it_changes(r.output, current);
  f.evidence = "after steps of the drive the recorded " + ch.name +
               " keeps moving, as creep operators draw it (the model's structure with them, " +
               std::string(models::to_string(kWithCreep)) + ": " + lags_of(r.side) +
               format("); modelled, it removes %.0f %% of the residual variance on the last ",
                      100.0 * f.explains) +
               format(
                   "%.3g s of the recording as a forecast (the structure with creep operators "
                   "identified on the first half, against the same structure without them: the "
                   "model had bent its loop to the creep)",
                   static_cast<double>(s.drive.size() - half) * s.sample_time);
  f.feature_name = "log10 time since the drive last stepped [s]";
  f.feature = log_time_since_step(s.drive, s.sample_time);
}

}  // namespace

std::optional<Reidentified> reidentified_leak(const models::TransducerModel& model,
                                              const Signals& s, const ChannelData& ch,
                                              const std::vector<double>& current,
                                              const Options& options, ShownBy evidence) {
  if (!ch.sensed || !reidentifiable(model, s, ch)) return std::nullopt;
  const Judge judge(model, s, ch);
  std::optional<Reidentified> r =
      judged_as_forecast(judge, ch, coarse_leaks(s), leak_neighbours, options, evidence);
  if (r) as_leak(*r, ch, s, current, as_forecast(judge, s, ch, "leak"));
  return r;
}

std::optional<Reidentified> reidentified_lag(
    const models::TransducerModel& model, const Signals& s, const ChannelData& ch,
    const std::vector<double>& current, const Options& options,
    const models::ChannelCorrection& mode_seed, LagSeen seen,
    const models::ChannelCorrection& named_modes, const Finding* named_lag) {
  if (!reidentifiable(model, s, ch)) return std::nullopt;
  const Judge judge(model, s, ch);
  const double most = static_cast<double>(models::kMaxCorrectionDelaySamples) * s.sample_time;
  const auto delay = [&](double seconds) {
    models::ChannelCorrection c;
    c.delay_s = std::min(seconds, most);
    return c;
  };
  // A quarter of a sample to 16 samples, doubling; then the best one's neighbours at a factor
  // 2^(1/2) and, around the better of those, 2^(1/4).
  std::vector<models::ChannelCorrection> grid;
  for (int doubling = -2; doubling <= 4; ++doubling)
    grid.push_back(delay(std::ldexp(s.sample_time, doubling)));
  const auto neighbours = [&](const models::ChannelCorrection& c) {
    std::vector<models::ChannelCorrection> out;
    for (const double f : {std::sqrt(2.0), 1.0 / std::sqrt(2.0), std::pow(2.0, 0.25),
                           std::pow(2.0, -0.25), std::pow(2.0, 0.75), std::pow(2.0, -0.75)}) {
      out.push_back(delay(c.delay_s * f));
    }
    return out;
  };
  const Trial null = judge.trial(models::ChannelCorrection{});
  if (null.forecast.empty()) return std::nullopt;
  Trial best;
  if (seen == LagSeen::kInRounds) {
    best = best_of(judge, grid, neighbours, null.start);
  } else {
    double last = std::numeric_limits<double>::infinity();
    int worse = 0;
    for (const models::ChannelCorrection& effect : grid) {
      Trial t = judge.trial(effect, null.start);
      worse = t.first_half_sse > last ? worse + 1 : 0;
      last = t.first_half_sse;
      if (t.first_half_sse < best.first_half_sse) best = std::move(t);
      if (worse == 2) break;
    }
    if (best.forecast.empty() ||
        1.0 - best.first_half_sse / null.first_half_sse < options.min_explains) {
      return std::nullopt;
    }
    for (const models::ChannelCorrection& effect : neighbours(best.effect)) {
      Trial t = judge.trial(effect, null.start);
      if (t.first_half_sse < best.first_half_sse) best = std::move(t);
    }
    best = in_full(judge, std::move(best));
  }
  if (best.forecast.empty()) return std::nullopt;
  // A fast, damped mode on S lags like a delay in the excitation's band; its resonance bends
  // the response the other way above it ((4 zeta^2 - 1) / w0^2 against the delay's tau^2 / 2
  // in s^2). Where the rounds fitted a mode, the modes around it (frequency within 2^(1/2),
  // damping within 2) are tried the same way, and one replaces the delay where the delay leaves
  // parsimony_ratio times its residual on the first half (the simpler lag otherwise).
  bool mode = false;
  Trial best_mode;
  if (!ch.sensed && mode_seed.dynamics_frequency_hz > 0.0) {
    const auto with_mode = [](double hz, double zeta) {
      models::ChannelCorrection c;
      c.dynamics_frequency_hz = hz;
      c.dynamics_damping = zeta;
      return c;
    };
    std::vector<models::ChannelCorrection> modes;
    for (const double f : {1.0 / std::sqrt(2.0), 1.0, std::sqrt(2.0)}) {
      for (const double z : {0.5, 1.0, 2.0}) {
        modes.push_back(
            with_mode(f * mode_seed.dynamics_frequency_hz, z * mode_seed.dynamics_damping));
      }
    }
    const auto mode_neighbours = [&](const models::ChannelCorrection& c) {
      std::vector<models::ChannelCorrection> out;
      for (const double f : {std::pow(2.0, 0.25), std::pow(2.0, -0.25)})
        out.push_back(with_mode(f * c.dynamics_frequency_hz, c.dynamics_damping));
      for (const double z : {std::sqrt(2.0), 1.0 / std::sqrt(2.0)})
        out.push_back(with_mode(c.dynamics_frequency_hz, z * c.dynamics_damping));
      return out;
    };
    best_mode = best_of(judge, modes, mode_neighbours, null.start);
    if (named_modes.dynamics_frequency_hz > 0.0) {
      // The rounds' two modes (or mode and direct path) as they were fitted, undone together.
      Trial block = in_full(judge, judge.trial(named_modes, null.start));
      if (block.first_half_sse < best_mode.first_half_sse) best_mode = std::move(block);
    }
    if (!best_mode.forecast.empty() &&
        best.first_half_sse > options.parsimony_ratio * best_mode.first_half_sse) {
      best = best_mode;  // a copy: read again below where a delay is carried in its place
      mode = true;
    }
  }
  std::optional<Reidentified> r = judged(judge, ch, null, best, options, ShownBy::kFitAndForecast);
  // A lag named alone (rounds or local pass): the delay carried, for the caller to weigh against
  // the correction after the model. In place of a named mode only where the delay is the simpler
  // form of the same lag on both halves: within parsimony_ratio of the modes' fit of the first
  // half (above) and no worse a forecast of the second.
  const bool in_place_of_mode = named_lag != nullptr && named_lag->effect == "dynamics";
  const bool carried = !r && !mode &&
                       ((named_lag != nullptr && named_lag->effect == "delay") ||
                        (in_place_of_mode && !best_mode.forecast.empty() &&
                         std::isfinite(best_mode.first_half_sse) &&
                         forecasts_no_worse(judge, ch, best, best_mode, options)));
  if (carried) {
    // The side identified on the whole record with the delay undone (Reidentified::carried).
    r = identified_whole(judge, best.effect, ch, named_lag->explains);
    if (!r) return std::nullopt;
    r->fit_explains = 1.0 - best.first_half_sse / null.first_half_sse;
    r->candidate = &candidate_using(CorrectionTerm::kDelay);
    r->terms = r->candidate->terms;
    r->carried = true;
    if (!in_place_of_mode) {
      r->finding = *named_lag;
      return r;
    }
    // Described by the caller once it has weighed the side against the mode (its share of the
    // residual on the judged rows goes into the text); until then the evidence holds what chose
    // the form.
    r->finding.effect = r->candidate->effect;
    r->finding.where = where_it_changes(r->output, current);
    r->finding.evidence = format(
        "as the simpler form of the lag the mode named took: the side identified on the "
        "first half with the delay undone leaves %.0f %% of its error there (with the best "
        "mode undone %.0f %%) and forecasts the last %.3g s no worse",
        100.0 * best.first_half_sse / null.first_half_sse,
        100.0 * best_mode.first_half_sse / null.first_half_sse,
        static_cast<double>(s.drive.size() - judge.half()) * s.sample_time);
    return r;
  }
  if (!r) return std::nullopt;
  const bool two =
      mode && (best.effect.dynamics2_frequency_hz > 0.0 || best.effect.dynamics_direct != 0.0);
  const CorrectionTerm term = !mode ? CorrectionTerm::kDelay
                              : two ? CorrectionTerm::kSecondMode
                                    : CorrectionTerm::kDynamics;
  r->candidate = &candidate_using(term);
  r->terms = r->candidate->terms;
  r->finding.effect = r->candidate->effect;
  r->finding.where = where_it_changes(r->output, current);
  describe(r->finding, *r->candidate, r->correction, ch, s, current, r->output,
           as_forecast(judge, s, ch, mode ? "mode" : "delay"));
  return r;
}

std::optional<Reidentified> reidentified_creep(const models::TransducerModel& model,
                                               const Signals& s, const ChannelData& ch,
                                               const std::vector<double>& current,
                                               const Options& options,
                                               const models::ChannelCorrection& beside) {
  if (model.structure != models::Structure::kHysteresis || !reidentifiable(model, s, ch)) {
    return std::nullopt;
  }
  const Judge as_is(model, s, ch);
  const Judge with_creep(s, ch, kWithCreep);
  const Trial null = as_is.trial(beside);
  const Trial creep = with_creep.trial(beside);
  const std::optional<double> explains =
      held_out_explains(as_is, null, with_creep, creep, ch, options, ShownBy::kFitAndForecast);
  if (!explains) return std::nullopt;
  std::optional<Reidentified> r = identified_whole(with_creep, beside, ch, *explains);
  if (!r) return std::nullopt;
  r->fit_explains = 1.0 - creep.first_half_sse / null.first_half_sse;
  as_creep(*r, ch, s, current, as_is.half());
  return r;
}

std::optional<CreepAndLeak> reidentified_creep_and_leak(const models::TransducerModel& model,
                                                        const Signals& s, const ChannelData& ch,
                                                        const std::vector<double>& current,
                                                        const Options& options) {
  if (model.structure != models::Structure::kHysteresis || !ch.sensed ||
      !reidentifiable(model, s, ch)) {
    return std::nullopt;
  }
  const Judge as_is(model, s, ch);
  const Judge with_creep(s, ch, kWithCreep);
  const Trial null = as_is.trial(models::ChannelCorrection{});
  const Trial creep = with_creep.trial(models::ChannelCorrection{});
  const Trial pair = best_leak(with_creep, s, creep.start);
  const std::optional<double> explains =
      held_out_explains(as_is, null, with_creep, pair, ch, options, ShownBy::kFitAndForecast);
  if (!explains) return std::nullopt;
  // Each part must carry the forecast: the pair beats the creep structure alone and the model's
  // structure with its own best leak.
  const Trial leak = best_leak(as_is, s, null.start);
  if (!forecast_explains(creep, pair, ch, as_is.half(), options, ShownBy::kForecast) ||
      !forecast_explains(leak, pair, ch, as_is.half(), options, ShownBy::kForecast)) {
    return std::nullopt;
  }
  std::optional<Reidentified> r = identified_whole(with_creep, pair.effect, ch, *explains);
  if (!r) return std::nullopt;
  r->fit_explains = 1.0 - pair.first_half_sse / null.first_half_sse;
  as_creep(*r, ch, s, current, as_is.half());
  CreepAndLeak out{*r, {}};
  as_leak(out.reidentified, ch, s, current,
          format("on the last %.3g s of the recording as a forecast (the structure with creep "
                 "operators identified on the first half with the leak undone, against it without "
                 "the leak and the model's structure with its own best leak: each alone had bent "
                 "its operators to the other's drift)",
                 static_cast<double>(s.drive.size() - as_is.half()) * s.sample_time));
  out.leak = out.reidentified.finding;
  out.reidentified.finding = r->finding;
  return out;
}

}  // namespace selfsense::diagnosis::detail
