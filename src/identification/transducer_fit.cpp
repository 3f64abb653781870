#include "selfsense/identification/transducer_fit.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <span>
#include <stdexcept>
#include <utility>
#include <vector>

#include "selfsense/identification/fit_quality.hpp"
#include "selfsense/identification/operator_fit.hpp"
#include "selfsense/identification/stress_hysteresis_fit.hpp"
#include "selfsense/models/stress_hysteresis.hpp"

namespace selfsense::identification {
namespace {

// OperatorStructure::row_step for n samples under IdentificationOptions::max_rows.
std::size_t row_step_for(const IdentificationOptions& o, std::size_t n) {
  return o.max_rows == 0 ? 1 : std::max<std::size_t>(1, (n + o.max_rows - 1) / o.max_rows);
}

OperatorStructure structure_of(const IdentificationOptions& o, bool creep, std::size_t n) {
  OperatorStructure s;
  s.plays = o.plays;
  s.eigenvalues = creep ? o.eigenvalues : 0;
  s.creep_plays = creep ? o.creep_plays : 0;
  s.dead_zones = o.dead_zones;
  s.estimate_history = o.estimate_history;
  s.fastest_eigenvalue = o.fastest_eigenvalue;
  s.slowest_eigenvalue = o.slowest_eigenvalue;
  s.bias_levels = o.bias_levels;
  s.start = o.start;
  s.row_step = row_step_for(o, n);
  return s;
}

// Sizes chosen on the fitting data alone: each candidate is fitted on the first three quarters
// and judged by its output error on the last quarter (the operator runs on from the start, so
// its memory there is the fit's own). Dead zones first (none or the given number), then the
// hinges per play with the dead zones chosen.
class SizeChooser {
 public:
  explicit SizeChooser(const OperatorSignals& s)
      : s_(s), split_(s.input.size() - s.input.size() / 4), y_(s.input.size()) {
    head_ = {s.input.first(split_), {}, s.output.first(split_), s.sample_time};
    for (const auto& u : s.linear_inputs)
      head_.linear_inputs.push_back(u.first(split_));
  }

  // Only the dead zones and the hinges vary between candidates: a pair judged before (the
  // chosen dead zones with the hinges they were judged with are the first hinge candidate
  // again) is not fitted twice.
  [[nodiscard]] double tail_rss(const OperatorStructure& structure) {
    const std::array<std::size_t, 2> key{structure.dead_zones, structure.bias_levels};
    for (const auto& [judged, rss] : judged_) {
      if (judged == key) return rss;
    }
    simulate_operator(fit_operator(head_, structure), s_.input, s_.linear_inputs, y_);
    double rss = 0.0;
    for (std::size_t k = split_; k < y_.size(); ++k)
      rss += (y_[k] - s_.output[k]) * (y_[k] - s_.output[k]);
    if (!std::isfinite(rss)) rss = std::numeric_limits<double>::infinity();
    judged_.emplace_back(key, rss);
    return rss;
  }

  // The candidate value of `field` with the smallest tail error (the first one on ties).
  template <typename Field>
  void choose(OperatorStructure& structure, Field OperatorStructure::*field,
              std::span<const Field> candidates) {
    Field best = structure.*field;
    double best_rss = std::numeric_limits<double>::infinity();
    for (const Field value : candidates) {
      structure.*field = value;
      const double rss = tail_rss(structure);
      if (rss < best_rss) {
        best_rss = rss;
        best = value;
      }
    }
    structure.*field = best;
  }

 private:
  const OperatorSignals& s_;
  std::size_t split_;
  OperatorSignals head_{};
  std::vector<double> y_;
  std::vector<std::pair<std::array<std::size_t, 2>, double>> judged_{};
};

OperatorModel fit_side(const OperatorSignals& s, OperatorStructure structure,
                       const IdentificationOptions& options, bool choose) {
  if (choose && s.input.size() >= 8) {
    SizeChooser chooser(s);
    if (options.choose_dead_zones && structure.dead_zones > 0) {
      const std::array<std::size_t, 2> dead_zones{0, structure.dead_zones};
      chooser.choose(structure, &OperatorStructure::dead_zones,
                     std::span<const std::size_t>(dead_zones));
    }
    if (options.choose_bias_levels) {
      chooser.choose(structure, &OperatorStructure::bias_levels,
                     std::span<const std::size_t>(kBiasLevelCandidates));
    }
  }
  return fit_operator(s, structure);
}

// The stress-hysteresis play count with the smallest reconstruction error on the last quarter
// of a fit on the first three (SizeChooser's split): T_hat from E and D, plus S_hat when the
// strain is recorded; without a sensed channel the strain's output error. The grid of n plays
// is not nested in that of m > n, and a denser grid matters (a generator off the grid: T_hat
// 3.8 / 2.4 / 0.11 % on new data with 16 / 24 / 48 plays, docs/identification.md).
std::size_t choose_stress_plays(const TransducerSignals& s, std::size_t fallback,
                                const StressCreepSizes& creep, std::size_t row_step,
                                LoopChange loop_change) {
  const std::size_t n = s.drive.size();
  const std::size_t split = n - n / 4;
  const auto head = [split](std::span<const double> v) { return v.empty() ? v : v.first(split); };
  const auto tail = [split](std::span<const double> v) { return v.subspan(split); };
  std::size_t best = kStressPlayCandidates.front();
  double best_score = std::numeric_limits<double>::infinity();
  std::vector<double> t_hat(n);
  std::vector<double> s_hat(n);
  const auto varies = [](std::span<const double> v) {
    const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
    return *hi > *lo;
  };
  if (!varies(head(s.stress)) || !varies(head(s.drive))) return fallback;  // nothing to fit
  for (const std::size_t plays : kStressPlayCandidates) {
    const models::StressHysteresisModel m =
        fit_stress_hysteresis(head(s.drive), head(s.stress), head(s.sensed), head(s.strain),
                              s.sample_time, plays, creep, ranking_row_step(row_step), loop_change);
    double score = 0.0;
    if (m.sensor) {
      models::StressHysteresisReconstructor rec(m);
      for (std::size_t k = 0; k < n; ++k) {
        const auto est = rec.step(s.drive[k], s.sensed[k]);
        t_hat[k] = est.stress;
        s_hat[k] = est.strain;
      }
      score = fit_quality(tail(s.stress), tail(t_hat)).nrmse;
      if (m.actuator) score += fit_quality(tail(s.strain), tail(s_hat)).nrmse;
    } else {
      models::StressHysteresisForward forward(m);
      for (std::size_t k = 0; k < n; ++k)
        s_hat[k] = forward.step(s.drive[k], s.stress[k]).strain;
      score = fit_quality(tail(s.strain), tail(s_hat)).nrmse;
    }
    if (std::isfinite(score) && score < best_score) {
      best_score = score;
      best = plays;
    }
  }
  return best;
}

models::InputRange range_of(std::span<const double> x) {
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  return {*lo, *hi};
}

}  // namespace

IdentificationOptions defaults_for(Structure s) noexcept {
  switch (s) {
    case Structure::kLinear:
      return {};
    case Structure::kPermittivity:
      return {0, 0, 0, 8, false, 0.0, 0.0};
    case Structure::kHysteresis:
    case Structure::kChargeDrive:
      return {24, 0, 0, 8, true, 0.0, 0.0};
    case Structure::kHysteresisCreep:
      return {24, 6, 2, 8, true, 0.0, 0.0};
    case Structure::kPreisachCreep:
      return {24, 6, 2, 8, true, 0.0, 0.0, 0, true, true};
    case Structure::kStressHysteresis:
      return {16, 0, 0, 0, true, 0.0, 0.0, 0, false, false, true};  // always estimates its start
  }
  return {};
}

TransducerModel identify(const TransducerSignals& signals, Structure structure,
                         const IdentificationOptions& options, const WorkRunner& run) {
  const std::size_t n = signals.drive.size();
  const auto usable = [n](std::span<const double> s) { return !s.empty() && s.size() == n; };
  if (n < 2) throw std::invalid_argument("identify: the drive signal needs at least 2 samples");
  if (!usable(signals.sensed) && !usable(signals.strain)) {
    throw std::invalid_argument("identify: needs the sensed channel or the strain to fit");
  }
  if (!signals.stress.empty() && signals.stress.size() != n) {
    throw std::invalid_argument("identify: stress and drive differ in length");
  }
  TransducerModel model;
  model.structure = structure;
  model.sample_time = signals.sample_time;
  model.drive_range = range_of(signals.drive);
  if (usable(signals.sensed)) model.sensed_range = range_of(signals.sensed);
  if (structure == Structure::kStressHysteresis) {
    if (signals.stress.empty()) {
      throw std::invalid_argument("identify: stress-hysteresis needs a stress channel (T or F)");
    }
    const StressCreepSizes creep{options.eigenvalues, options.creep_plays,
                                 options.fastest_eigenvalue, options.slowest_eigenvalue};
    const std::size_t row_step = row_step_for(options, n);
    const std::size_t plays =
        options.choose_plays && n >= 8
            ? choose_stress_plays(signals, options.plays, creep, row_step, options.loop_change)
            : options.plays;
    model.vectorial =
        fit_stress_hysteresis(signals.drive, signals.stress, signals.sensed, signals.strain,
                              signals.sample_time, plays, creep, row_step, options.loop_change);
    return model;
  }
  std::vector<std::span<const double>> linear;
  if (!signals.stress.empty()) linear.push_back(signals.stress);

  const bool creep =
      structure == Structure::kHysteresisCreep || structure == Structure::kPreisachCreep;
  const bool choose = structure == Structure::kPreisachCreep;
  // The sides share nothing but the signals they read: each is one piece of work for `run`.
  std::optional<OperatorModel> sensor;
  std::optional<OperatorModel> actuator;
  std::vector<double> squared;
  std::vector<std::span<const double>> actuator_inputs = linear;
  // The actuator side of the permittivity and charge-drive models is linear (eq. 6, 19); with
  // charge drive it also has the electrostrictive term S ~ D^2, which makes the butterfly strain
  // loops of bipolar drive past the coercive field.
  const bool linear_side =
      structure == Structure::kPermittivity || structure == Structure::kChargeDrive;
  if (usable(signals.strain) && structure == Structure::kChargeDrive) {
    squared.resize(n);
    for (std::size_t k = 0; k < n; ++k)
      squared[k] = signals.drive[k] * signals.drive[k];
    actuator_inputs.emplace_back(squared);
  }
  std::vector<std::function<void()>> work;
  if (usable(signals.sensed)) {
    work.emplace_back([&] {
      sensor = fit_side({signals.drive, linear, signals.sensed, signals.sample_time},
                        structure_of(options, creep, n), options, choose);
    });
  }
  if (usable(signals.strain)) {
    work.emplace_back([&] {
      actuator = fit_side({signals.drive, actuator_inputs, signals.strain, signals.sample_time},
                          linear_side ? OperatorStructure{} : structure_of(options, creep, n),
                          options, choose && !linear_side);
    });
  }
  if (run && work.size() > 1) {
    run(work);
  } else {
    for (const auto& piece : work)
      piece();
  }
  model.sensor = std::move(sensor);
  model.actuator = std::move(actuator);
  if (model.actuator && !squared.empty()) {
    model.actuator->quadratic = model.actuator->linear_gains.back();
    model.actuator->linear_gains.pop_back();
  }
  return model;
}

}  // namespace selfsense::identification
