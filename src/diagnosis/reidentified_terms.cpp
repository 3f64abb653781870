// A side re-identified with an effect's terms undone: the temperature's, and the stress's on D
// (reidentified.hpp). Pure math.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>

#include "candidates.hpp"
#include "held_out.hpp"
#include "reidentified.hpp"
#include "selfsense/identification/transducer_fit.hpp"
#include "text.hpp"

namespace selfsense::diagnosis::detail {
namespace {

using identification::CorrectionSignals;
using identification::CorrectionTerm;

constexpr int kAlternations = 3;  // terms, then side, each time on the other's latest

// The temperature's side from the record's start (reidentified.hpp): the stretch where the
// temperature stays within this share of its recorded range of the first sample's ...
constexpr double kNearReferenceBand = 0.3;
// ... used where it holds at least this share of the record (a stack near its reference long
// enough to carry the side) ...
constexpr double kMinNearReferenceShare = 0.2;
// ... and the side identified on at least this share (the operators need the excitation's
// variety more than the temperature's flatness).
constexpr double kMinStartSideShare = 1.0 / 3.0;

// The channel's side and a candidate's terms identified together.
struct Joint {
  models::TransducerModel model{};
  models::ChannelCorrection correction{};
  std::vector<double> base{};    // the side's output over the whole record
  std::vector<double> output{};  // ... through the terms
  double fit_sse{std::numeric_limits<double>::infinity()};  // over the fitting samples
};

class Identifier {
 public:
  // `side_samples`: the joint's side is identified on the record's first side_samples samples.
  Identifier(const models::TransducerModel& model, const Signals& s, const ChannelData& ch,
             std::size_t side_samples)
      : model_(model), s_(s), ch_(ch), side_samples_(side_samples) {}

  // The structure's side of this channel identified on the first `samples` samples of
  // `channel` (all of them by default).
  [[nodiscard]] models::TransducerModel identify(std::span<const double> channel,
                                                 std::size_t samples = kAll) const {
    const std::size_t k = std::min(samples, channel.size());
    identification::TransducerSignals t;
    t.drive = s_.drive.first(k);
    (ch_.sensed ? t.sensed : t.strain) = channel.first(k);
    t.stress = s_.stress.empty() ? s_.stress : s_.stress.first(k);
    t.sample_time = s_.sample_time;
    return identification::identify(t, model_.structure,
                                    reidentification_options(model_.structure));
  }

  [[nodiscard]] std::vector<double> output_of(const models::TransducerModel& m) const {
    const Outputs o = simulate(m, s_);
    std::vector<double> y = ch_.sensed ? o.sensed : o.strain;
    static_cast<void>(hold_finite(y));
    return y;
  }

  // The side's coupling: the stress's terms read the response to the drive alone, y - d T.
  [[nodiscard]] double coupling(const models::TransducerModel& m) const {
    return coupling_of(ch_.sensed ? m.sensor : m.actuator);
  }

  // `response`: y - d T over the record (its storage outlives the signals).
  [[nodiscard]] CorrectionSignals signals(std::span<const double> y,
                                          std::span<const double> response) const {
    CorrectionSignals cs;
    cs.y = y;
    cs.response = response;
    cs.recorded = ch_.recorded;
    cs.drive = s_.drive;
    cs.stress = s_.stress;
    cs.temperature = s_.temperature;
    cs.sample_time = s_.sample_time;
    if (!s_.temperature.empty()) cs.temperature_reference_degc = s_.temperature[0];
    return cs;
  }

  // The recording with the terms undone. They are affine in the model's output per sample,
  // v = a y + b, so a and b come from the terms run on y = 0 and y = 1.
  // The side's coupling d: the response is y - d T at y = 0 and 1.
  [[nodiscard]] std::vector<double> undone(const models::ChannelCorrection& c, double d) const {
    const std::size_t n = s_.drive.size();
    const std::vector<double> zero(n, 0.0);
    const std::vector<double> one(n, 1.0);
    const std::vector<double> r0 = response_to_drive(zero, d, s_.stress);
    const std::vector<double> r1 = response_to_drive(one, d, s_.stress);
    const std::vector<double> b = identification::apply_correction(signals(zero, r0), c);
    const std::vector<double> ab = identification::apply_correction(signals(one, r1), c);
    std::vector<double> out(n);
    for (std::size_t k = 0; k < n; ++k)
      out[k] = (ch_.recorded[k] - b[k]) / (ab[k] - b[k]);
    return out;
  }

  // Alternates terms (fitted on `rows`) and the side (identified on its samples with the terms
  // undone). Throws as identification does.
  [[nodiscard]] Joint joint(std::span<const CorrectionTerm> terms,
                            const std::vector<bool>& rows) const {
    Joint j;
    j.model = identify(ch_.recorded, side_samples_);
    Joint best;
    for (int i = 0;; ++i) {
      j.base = output_of(j.model);
      const double d = coupling(j.model);
      const std::vector<double> response = response_to_drive(j.base, d, s_.stress);
      const identification::CorrectionFit fit =
          identification::fit_correction(signals(j.base, response), terms, {}, rows);
      j.correction = fit.correction;
      j.output = fit.output;
      j.fit_sse = fit.fit_sse;
      // The side minimises its own identification's error on the undone record, not this one:
      // the alternation need not descend, so the best pass on the fitting rows is kept.
      if (j.fit_sse < best.fit_sse) best = j;
      if (i == kAlternations) return best;
      j.model = identify(undone(j.correction, d), side_samples_);
    }
  }

 private:
  static constexpr std::size_t kAll = std::numeric_limits<std::size_t>::max();
  const models::TransducerModel& model_;
  const Signals& s_;
  const ChannelData& ch_;
  std::size_t side_samples_;
};

const Candidate& temperature_candidate(bool quadratic) {
  for (const Candidate& c : candidates()) {
    if (uses_term(c, CorrectionTerm::kTemperature) &&
        uses_term(c, CorrectionTerm::kTemperatureQuadratic) == quadratic) {
      return c;
    }
  }
  throw std::logic_error("reidentified_temperature: no candidate");
}

// The stress's candidate for the channel with the most terms (on D each part of the response
// apart: the permittivity, the loop and the coupling).
const Candidate* stress_candidate(const ChannelData& ch, const Signals& s) {
  const Candidate* best = nullptr;
  for (const Candidate& c : candidates()) {
    if (!uses_term(c, CorrectionTerm::kStress) || !applicable(c, ch, s, false, false)) continue;
    if (best == nullptr || c.terms.size() > best->terms.size()) best = &c;
  }
  return best;
}

// The side (on the first `side_samples` samples) and a candidate's terms identified together
// (Identifier::joint), judged on held-out blocks against the side identified on the record as
// it is. `ladder`: nested candidates, each replacing the one before where it beats it on the
// held-out blocks (test and block rule, no effect size: a nested model).
std::optional<Reidentified> reidentified_with_terms(
    const models::TransducerModel& model, const Signals& s, const ChannelData& ch,
    const std::vector<double>& current, const Options& options,
    std::span<const Candidate* const> ladder, const std::string& judged, std::size_t side_samples) {
  const std::size_t n = s.drive.size();
  const Identifier id(model, s, ch, side_samples);
  std::vector<double> null_output;
  Joint best;
  const Candidate* candidate = nullptr;
  Rows rows;
  try {
    null_output = id.output_of(id.identify(ch.recorded));
    rows = make_rows(hold_finite(null_output), options.blocks);
    for (const Candidate* next : ladder) {
      Joint j = id.joint(next->terms, rows.fit);
      if (candidate == nullptr ||
          passes_blocks(block_explains(ch.recorded, best.output, j.output, rows), options)) {
        best = std::move(j);
        candidate = next;
      }
    }
  } catch (const std::invalid_argument&) {
    return std::nullopt;
  }
  if (candidate == nullptr) return std::nullopt;
  const double null_sse = sse_over(ch.recorded, null_output, rows.judge);
  const double joint_sse = sse_over(ch.recorded, best.output, rows.judge);
  if (!(null_sse > 0.0)) return std::nullopt;
  const double explains = 1.0 - joint_sse / null_sse;
  if (explains < options.min_explains ||
      !passes_blocks(block_explains(ch.recorded, null_output, best.output, rows), options)) {
    return std::nullopt;
  }

  Reidentified r;
  try {
    const Joint whole = id.joint(candidate->terms, std::vector<bool>(n, true));
    const std::optional<models::SideModel>& side =
        ch.sensed ? whole.model.sensor : whole.model.actuator;
    if (!side) return std::nullopt;
    r.side = *side;
    r.correction = whole.correction;
    r.base = whole.base;
    r.output = whole.output;
  } catch (const std::invalid_argument&) {
    return std::nullopt;
  }
  r.terms = candidate->terms;
  r.candidate = candidate;
  Finding& f = r.finding;
  f.effect = candidate->effect;
  f.channel = ch.name;
  f.explains = explains;
  f.where = where_it_changes(r.output, current);
  describe(f, *candidate, r.correction, ch, s, current, r.output, judged);
  return r;
}

// The samples from the start while the temperature stays within kNearReferenceBand of its
// range of the first sample's.
std::size_t near_reference(std::span<const double> theta) {
  const double band = kNearReferenceBand * range_of(theta);
  std::size_t k = 0;
  while (k < theta.size() && std::abs(theta[k] - theta[0]) <= band)
    ++k;
  return k;
}

// Field-drive models with one side for the channel.
bool has_own_side(const models::TransducerModel& model, const ChannelData& ch) {
  const bool has_side = ch.sensed ? model.sensor.has_value() : model.actuator.has_value();
  return model.drive() == models::Drive::kField && !model.vectorial && has_side;
}

}  // namespace

std::optional<Reidentified> reidentified_temperature(const models::TransducerModel& model,
                                                     const Signals& s, const ChannelData& ch,
                                                     const std::vector<double>& current,
                                                     const Options& options) {
  const std::size_t n = s.drive.size();
  if (!has_own_side(model, ch) || n < 1000 || s.temperature.size() != n ||
      range_of(s.temperature) <= 1.0) {
    return std::nullopt;
  }
  // Without T the re-identified side would lose the model's stress coupling.
  if (ch.coupling != 0.0 && s.stress.empty()) return std::nullopt;
  const std::array<const Candidate*, 2> ladder{&temperature_candidate(false),
                                               &temperature_candidate(true)};
  const std::string against = "against the structure identified on " + ch.name +
                              " as recorded: the model had bent its own operators to the "
                              "temperature)";
  const std::size_t near = near_reference(s.temperature);
  if (static_cast<double>(near) >= kMinNearReferenceShare * static_cast<double>(n)) {
    const std::size_t side = std::max(
        near, static_cast<std::size_t>(std::ceil(kMinStartSideShare * static_cast<double>(n))));
    std::optional<Reidentified> r = reidentified_with_terms(
        model, s, ch, current, options, ladder,
        format("on held-out blocks (the model's structure identified on the record's first "
               "%.0f s, the stack within %.0f %% of the temperature's range of its start for the "
               "first %.0f s, with the temperature's terms undone, the terms fitted on the other "
               "blocks of the whole record, ",
               static_cast<double>(side) * s.sample_time, 100.0 * kNearReferenceBand,
               static_cast<double>(near) * s.sample_time) +
            against,
        side);
    if (r) return r;
  }
  return reidentified_with_terms(
      model, s, ch, current, options, ladder,
      "on held-out blocks (the model's structure identified with the temperature's terms "
      "undone, the terms fitted on the other blocks, " +
          against,
      n);
}

std::optional<Reidentified> reidentified_stress_terms(const models::TransducerModel& model,
                                                      const Signals& s, const ChannelData& ch,
                                                      const std::vector<double>& current,
                                                      const Options& options) {
  const std::size_t n = s.drive.size();
  // Both channels. S was left out while the joint read the terms on y (the validation S of 4 of
  // 10 development draws 1.1-2x worse): the model runs them on the response y - d T, so the
  // model returned differed from the one judged by k s T^2 on S (k d T^2 on D). Read on the
  // response (Identifier), 3800037's validation S is 0.14 % where it was 6.07 %.
  if (!has_own_side(model, ch) || n < 1000 || s.stress.size() != n) {
    return std::nullopt;
  }
  const Candidate* candidate = stress_candidate(ch, s);
  if (candidate == nullptr) return std::nullopt;
  const std::array<const Candidate*, 1> ladder{candidate};
  return reidentified_with_terms(
      model, s, ch, current, options, ladder,
      "on held-out blocks (the model's structure identified with the stress's terms undone, "
      "the terms fitted on the other blocks, against the structure identified on " +
          ch.name + " as recorded: the model had bent its own operators to the stress)",
      n);
}

}  // namespace selfsense::diagnosis::detail
