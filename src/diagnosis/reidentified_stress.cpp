// Stress dependence re-identified with the stress-hysteresis structure (reidentified.hpp). Pure
// math.
#include <algorithm>
#include <cmath>
#include <span>
#include <stdexcept>
#include <utility>
#include <vector>

#include "candidates.hpp"
#include "held_out.hpp"
#include "reidentified.hpp"
#include "selfsense/identification/transducer_fit.hpp"
#include "text.hpp"

namespace selfsense::diagnosis::detail {
namespace {

using models::Structure;

// A stress whose part apart from the field is below this share of its magnitude is constant to
// the recording's precision (a CSV's 17 digits, the simulation's rounding).
constexpr double kConstantStress = 1e-9;

// The structure identified on samples [begin, end) of both channels.
models::TransducerModel identified(const Signals& s, Structure structure, std::size_t begin,
                                   std::size_t end) {
  const auto first = [begin, end](std::span<const double> x) {
    return x.empty() ? x : x.subspan(begin, end - begin);
  };
  identification::TransducerSignals t;
  t.drive = first(s.drive);
  t.sensed = first(s.sensed);
  t.stress = first(s.stress);
  t.strain = first(s.strain);
  t.sample_time = s.sample_time;
  return identification::identify(t, structure, reidentification_options(structure));
}

std::vector<double> channel_of(const Outputs& o, const ChannelData& ch) {
  std::vector<double> y = ch.sensed ? o.sensed : o.strain;
  static_cast<void>(hold_finite(y));
  return y;
}

// A structure judged by two-fold cross-validation over the halves of the record: identified on
// each half, each half forecast by the model that did not see it.
struct CrossFit {
  Outputs first;   // identified on the first half
  Outputs second;  // ... on the second
};

CrossFit cross_fit(const Signals& s, Structure structure) {
  const std::size_t n = s.drive.size();
  const std::size_t half = n / 2;
  CrossFit c;
  c.first = simulate(identified(s, structure, 0, half), s);
  c.second = simulate(identified(s, structure, half, n), s);
  return c;
}

// The same for the model's own structure, whose sides are identified apart: the first half's
// are the channels' nulls (first_half_fit), identified once for every judgement, where the
// channels are every side the recording has.
CrossFit cross_fit(const Signals& s, Structure structure,
                   const std::vector<ChannelData>& channels) {
  const std::size_t n = s.drive.size();
  const auto has = [&](bool sensed) {
    return std::any_of(channels.begin(), channels.end(),
                       [sensed](const ChannelData& ch) { return ch.sensed == sensed; });
  };
  if (channels.empty() || (!s.sensed.empty() && !has(true)) || (!s.strain.empty() && !has(false))) {
    return cross_fit(s, structure);
  }
  models::TransducerModel first = first_half_fit(structure, s, channels.front());
  for (std::size_t i = 1; i < channels.size(); ++i) {
    models::TransducerModel m = first_half_fit(structure, s, channels[i]);
    if (channels[i].sensed) {
      first.sensor = std::move(m.sensor);
      first.sensed_range = m.sensed_range;
    } else {
      first.actuator = std::move(m.actuator);
    }
  }
  CrossFit c;
  c.first = simulate(first, s);
  c.second = simulate(identified(s, structure, n / 2, n), s);
  return c;
}

// The channel as each half's unseen model forecasts it.
std::vector<double> unseen(const CrossFit& c, const ChannelData& ch) {
  const std::vector<double> a = channel_of(c.first, ch);
  const std::vector<double> b = channel_of(c.second, ch);
  const std::size_t half = a.size() / 2;
  std::vector<double> out(a.size());
  for (std::size_t k = 0; k < out.size(); ++k)
    out[k] = k < half ? b[k] : a[k];
  return out;
}

// The part of the stress that the field does not explain: T less its least-squares fit on an
// offset, E and the base's outputs (a load spring makes T follow the strain), by modified
// Gram-Schmidt on the centred columns. Its RMS.
double independent_stress_rms(const Signals& s, const std::vector<ChannelData>& channels) {
  const std::size_t n = s.stress.size();
  const auto centred = [n](std::span<const double> x) {
    double mean = 0.0;
    for (const double v : x)
      mean += v / static_cast<double>(n);
    std::vector<double> c(x.begin(), x.end());
    for (double& v : c)
      v -= mean;
    return c;
  };
  const auto dot = [n](const std::vector<double>& a, const std::vector<double>& b) {
    double sum = 0.0;
    for (std::size_t k = 0; k < n; ++k)
      sum += a[k] * b[k];
    return sum;
  };
  std::vector<std::vector<double>> basis;
  const auto project_out = [&](std::vector<double>& x) {
    for (const std::vector<double>& q : basis) {
      const double c = dot(x, q);
      for (std::size_t k = 0; k < n; ++k)
        x[k] -= c * q[k];
    }
  };
  std::vector<std::span<const double>> columns{s.drive};
  for (const ChannelData& ch : channels)
    columns.emplace_back(ch.base);
  for (const std::span<const double> column : columns) {
    std::vector<double> q = centred(column);
    const double before = std::sqrt(dot(q, q));
    project_out(q);
    const double norm = std::sqrt(dot(q, q));
    if (!(norm > 1e-9 * before)) continue;  // collinear with the columns before it
    for (double& v : q)
      v /= norm;
    basis.push_back(std::move(q));
  }
  std::vector<double> t = centred(s.stress);
  project_out(t);
  return std::sqrt(dot(t, t) / static_cast<double>(n));
}

// The rules of a round with the folds as the unit of harm: the gain significant over the blocks
// (each forecast by the model that did not see it), and neither half, forecast by one model
// identified on the other, worse by more than a round lets one held-out block be. Within a half
// the blocks share their model, so a stretch it forecasts less well is not another trial of how
// the structure carries over.
bool forecasts_better(std::span<const double> recorded, const std::vector<double>& null,
                      const std::vector<double>& stressed, const Rows& rows,
                      const Options& options) {
  const BlockShares blocks = block_explains(recorded, null, stressed, rows);
  Rows halves = rows;
  const std::size_t n = recorded.size();
  for (std::size_t k = 0; k < n; ++k)
    halves.block[k] = k < n / 2 ? 1 : 3;
  halves.blocks = 4;
  const BlockShares folds = block_explains(recorded, null, stressed, halves);
  return blocks.test.significant &&
         folds.worst >= -std::max(options.max_block_loss, blocks.explains);
}

}  // namespace

std::optional<StressReidentified> reidentified_stress(const models::TransducerModel& model,
                                                      const Signals& s,
                                                      const std::vector<ChannelData>& channels,
                                                      const Options& options) {
  const std::size_t n = s.drive.size();
  if (model.drive() != models::Drive::kField || model.vectorial || n < 1000 ||
      s.stress.size() != n || !(range_of(s.stress) > 0.0)) {
    return std::nullopt;
  }
  // The stress's dependence can be told from the field's own only where the load moves apart
  // from the field: under a constant preload (T constant to rounding, which its range does not
  // see) the structure's stress columns repeat its field columns and it is only another model
  // of the field.
  double magnitude = 0.0;
  for (const double t : s.stress)
    magnitude = std::max(magnitude, std::abs(t));
  if (!(independent_stress_rms(s, channels) > kConstantStress * magnitude)) return std::nullopt;
  CrossFit null;
  CrossFit stressed;
  try {
    null = cross_fit(s, model.structure, channels);
    stressed = cross_fit(s, Structure::kStressHysteresis);
  } catch (const std::invalid_argument&) {
    return std::nullopt;
  }
  // Every sample is judged, by the model identified on the other half, in as many blocks per
  // half as a round has.
  Rows rows;
  rows.blocks = 2 * options.blocks;
  rows.fit.assign(n, false);
  rows.judge.assign(n, true);
  rows.block.resize(n);
  for (std::size_t k = 0; k < n; ++k)
    rows.block[k] = 2 * std::min(options.blocks - 1, k * options.blocks / n) + 1;
  StressReidentified r;
  for (const ChannelData& ch : channels) {
    const std::vector<double> a = unseen(null, ch);
    const std::vector<double> b = unseen(stressed, ch);
    const double null_sse = sse_over(ch.recorded, a, rows.judge);
    const double stress_sse = sse_over(ch.recorded, b, rows.judge);
    if (!(null_sse > 0.0)) return std::nullopt;
    // A channel the structure forecasts worse keeps the model's side.
    if (stress_sse > null_sse) {
      r.kept.push_back(ch.name);
      continue;
    }
    // The unseen halves by the rules of a round with the halves as the unit of harm
    // (forecasts_better); the identification's own evidence is the whole record's, below.
    const double explains = 1.0 - stress_sse / null_sse;
    if (explains < options.min_explains || !forecasts_better(ch.recorded, a, b, rows, options)) {
      continue;
    }
    Finding f;
    f.effect = candidate_using(identification::CorrectionTerm::kStress).effect;
    f.channel = ch.name;
    f.explains = explains;
    r.named.push_back(std::move(f));
  }
  if (r.named.empty()) return std::nullopt;
  try {
    r.model = identified(s, Structure::kStressHysteresis, 0, n);
    for (const ChannelData& ch : channels) {
      if (r.replaces(ch.name)) continue;
      if (ch.sensed) {
        r.model.vectorial->sensor.reset();
        r.model.sensor = model.sensor;
      } else {
        r.model.vectorial->actuator.reset();
        r.model.actuator = model.actuator;
      }
    }
    r.outputs = simulate(r.model, s);
  } catch (const std::invalid_argument&) {
    return std::nullopt;
  }
  // The identification's own evidence, for the model that replaces the given one: on the whole
  // record it must fit no channel worse than that model, and a named channel stays named only
  // where it fits it by min_explains better. (Each half's structure against each half's null
  // is not asked too: the null's creep operators can fit a half better and forecast the other
  // worse, the bend this judges; 900004's D fitted its halves 23 % worse, forecast them 55 %
  // better and fitted the whole record 59 % better than the model, and was replaced unnamed.)
  for (const ChannelData& ch : channels) {
    const std::vector<double> output = channel_of(r.outputs, ch);
    const double replaced_sse = sse_over(ch.recorded, ch.base, rows.judge);
    const double whole_sse = sse_over(ch.recorded, output, rows.judge);
    if (!(whole_sse <= replaced_sse)) return std::nullopt;
    if (!(whole_sse <= (1.0 - options.min_explains) * replaced_sse)) {
      std::erase_if(r.named, [&](const Finding& f) { return f.channel == ch.name; });
    }
  }
  if (r.named.empty()) return std::nullopt;
  std::vector<double> stress_mpa(n);
  for (std::size_t k = 0; k < n; ++k)
    stress_mpa[k] = 1e-6 * s.stress[k];
  for (Finding& f : r.named) {
    const auto ch = std::find_if(channels.begin(), channels.end(),
                                 [&](const ChannelData& c) { return c.name == f.channel; });
    const std::vector<double> output = channel_of(r.outputs, *ch);
    f.where = where_it_changes(output, ch->base);
    f.evidence =
        "the recorded " + f.channel +
        " follows the stress beyond the model's affine coupling: the loop and the coupling "
        "change with T (the stress-hysteresis structure, D or S = W0.q + T W1.q + d1 T + d2 T^2, "
        "identified on each half, forecasts the other " +
        format(
            "with %.0f %% less residual variance than the model's structure identified the "
            "same way: the model had bent its own operators to the stress)",
            100.0 * f.explains);
    for (const std::string& other : r.kept) {
      f.evidence += "; " + other +
                    " keeps the model's own side, which forecasts it better than the structure";
    }
    f.feature_name = "stress T [MPa]";
    f.feature = stress_mpa;
  }
  return r;
}

}  // namespace selfsense::diagnosis::detail
