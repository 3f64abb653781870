#include "reidentified.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "candidates.hpp"
#include "held_out.hpp"
#include "selfsense/identification/transducer_fit.hpp"
#include "text.hpp"

namespace selfsense::diagnosis::detail {
namespace {

// A leak, and what it costs to judge: the model identified on D with it undone.
struct Trial {
  models::ChannelCorrection leak{};
  std::vector<double> forecast{};  // the identified model's D through the leak, whole record
  double first_half_sse{std::numeric_limits<double>::infinity()};
};

class Judge {
 public:
  Judge(const models::TransducerModel& model, const Signals& s)
      : model_(model), s_(s), half_(s.drive.size() / 2) {}

  [[nodiscard]] std::size_t half() const { return half_; }

  // D as the model would see it without the leak (the correction stage's inverse).
  [[nodiscard]] std::vector<double> undone(const models::ChannelCorrection& leak) const {
    std::vector<double> out(s_.sensed.begin(), s_.sensed.end());
    if (leak.empty()) return out;
    models::CorrectionStage stage(leak, s_.sample_time);
    for (std::size_t k = 0; k < out.size(); ++k) {
      models::CorrectionStage::Inputs in;
      in.drive = s_.drive[k];
      out[k] = stage.invert(s_.sensed[k], in);
    }
    return out;
  }

  // The structure's sensor side identified on D with the leak undone over `samples` samples;
  // its D over the whole record.
  [[nodiscard]] models::TransducerModel identify(const std::vector<double>& d,
                                                 std::size_t samples) const {
    const auto first = [samples](std::span<const double> x) {
      return x.empty() ? x : x.first(samples);
    };
    identification::TransducerSignals t;
    t.drive = first(s_.drive);
    t.sensed = std::span<const double>(d).first(samples);
    t.stress = first(s_.stress);
    t.sample_time = s_.sample_time;
    return identification::identify(t, model_.structure,
                                    identification::defaults_for(model_.structure));
  }

  [[nodiscard]] std::vector<double> forecast(const models::TransducerModel& m,
                                             const models::ChannelCorrection& leak) const {
    std::vector<double> d = simulate(m, s_).sensed;
    static_cast<void>(hold_finite(d));
    if (leak.empty()) return d;
    identification::CorrectionSignals cs;
    cs.y = d;
    cs.drive = s_.drive;
    cs.sample_time = s_.sample_time;
    return identification::apply_correction(cs, leak);
  }

  [[nodiscard]] Trial trial(const models::ChannelCorrection& leak) const {
    Trial t;
    t.leak = leak;
    try {
      t.forecast = forecast(identify(undone(leak), half_), leak);
    } catch (const std::invalid_argument&) {
      return t;  // no identification with this leak undone: not a candidate
    }
    double sse = 0.0;
    for (std::size_t k = 0; k < half_; ++k) {
      const double e = s_.sensed[k] - t.forecast[k];
      sse += e * e;
    }
    if (std::isfinite(sse)) t.first_half_sse = sse;
    return t;
  }

 private:
  const models::TransducerModel& model_;
  const Signals& s_;
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

const Candidate& leak_candidate(const models::ChannelCorrection& leak) {
  const CorrectionTerm term =
      leak.leakage_tau_s > 0.0 ? CorrectionTerm::kLeakage : CorrectionTerm::kDriveIntegral;
  for (const Candidate& c : candidates()) {
    if (uses_term(c, term)) return c;
  }
  throw std::logic_error("reidentified_leak: no candidate for the leak");
}

}  // namespace

Rows forecast_rows(std::size_t n, std::size_t half, std::size_t judging,
                   const std::vector<double>& a, const std::vector<double>& b) {
  Rows r;
  r.blocks = 2 * judging;
  r.fit.assign(n, false);
  r.judge.assign(n, false);
  r.block.assign(n, 0);
  for (std::size_t k = 0; k < n; ++k) {
    const bool finite = std::isfinite(a[k]) && std::isfinite(b[k]);
    if (k < half) {
      r.fit[k] = finite;
      continue;
    }
    r.judge[k] = finite;
    r.block[k] = 2 * std::min(judging - 1, (k - half) * judging / (n - half)) + 1;
  }
  return r;
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

std::optional<Reidentified> reidentified_leak(const models::TransducerModel& model,
                                              const Signals& s, const ChannelData& ch,
                                              const std::vector<double>& current,
                                              const Options& options) {
  const std::size_t n = s.drive.size();
  if (!ch.sensed || model.drive() != models::Drive::kField || model.vectorial || !model.sensor ||
      s.sensed.size() != n || n < 1000) {
    return std::nullopt;
  }
  // Without T the re-identified sensor side would lose the model's stress coupling.
  if (ch.coupling != 0.0 && s.stress.empty()) return std::nullopt;
  const Judge judge(model, s);
  const Trial null = judge.trial(models::ChannelCorrection{});
  if (null.forecast.empty()) return std::nullopt;

  Trial best;
  for (const models::ChannelCorrection& leak : coarse_leaks(s)) {
    Trial t = judge.trial(leak);
    if (t.first_half_sse < best.first_half_sse) best = std::move(t);
  }
  if (best.forecast.empty()) return std::nullopt;
  for (const double factor : {std::sqrt(3.0), 1.0 / std::sqrt(3.0)}) {
    Trial t = judge.trial(scaled(best.leak, factor));
    if (t.first_half_sse < best.first_half_sse) best = std::move(t);
  }
  // The leak must be the structure's own finding too: with it undone the identification fits
  // the first half by min_explains better (on clean stacks a small leak of either sign mends
  // the forecast of a model of another class a little; it does not change the fit).
  if (best.forecast.empty() ||
      1.0 - best.first_half_sse / null.first_half_sse < options.min_explains) {
    return std::nullopt;
  }

  const Rows rows = forecast_rows(n, judge.half(), options.blocks, null.forecast, best.forecast);
  const double null_sse = sse_over(ch.recorded, null.forecast, rows.judge);
  const double leak_sse = sse_over(ch.recorded, best.forecast, rows.judge);
  if (!(null_sse > 0.0)) return std::nullopt;
  const double explains = 1.0 - leak_sse / null_sse;
  if (explains < options.min_explains ||
      !passes_blocks(block_explains(ch.recorded, null.forecast, best.forecast, rows), options)) {
    return std::nullopt;
  }

  Reidentified r;
  r.correction = best.leak;
  try {
    const models::TransducerModel whole = judge.identify(judge.undone(best.leak), n);
    if (!whole.sensor) return std::nullopt;
    r.side = *whole.sensor;
    r.base = judge.forecast(whole, models::ChannelCorrection{});
    r.output = judge.forecast(whole, best.leak);
  } catch (const std::invalid_argument&) {
    return std::nullopt;
  }
  Finding& f = r.finding;
  f.effect = "charge_leakage";
  f.channel = ch.name;
  f.explains = explains;
  f.where = where_it_changes(r.output, current);
  const std::string judged = format(
      "on the last %.3g s of the recording as a forecast (the model's structure identified on "
      "the first half with the leak undone, against the same structure identified on D as "
      "recorded: the model had bent its own operators to the leak)",
      static_cast<double>(n - judge.half()) * s.sample_time);
  r.candidate = &leak_candidate(best.leak);
  r.terms = {best.leak.leakage_tau_s > 0.0 ? CorrectionTerm::kLeakage
                                           : CorrectionTerm::kDriveIntegral};
  describe(f, *r.candidate, best.leak, ch, s, current, r.output, judged);
  return r;
}

}  // namespace selfsense::diagnosis::detail
