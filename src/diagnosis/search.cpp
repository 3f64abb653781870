#include "search.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string_view>

#include "text.hpp"

namespace selfsense::diagnosis::detail {
namespace {

// The filters a fit `found` chose, into `start` where it has none of its own (so a refit keeps
// them, not searching again): the longer leak and delay, the modes.
void take_filters(ChannelCorrection& start, const ChannelCorrection& found) {
  start.leakage_tau_s = std::max(start.leakage_tau_s, found.leakage_tau_s);
  start.delay_s = std::max(start.delay_s, found.delay_s);
  if (start.dynamics_frequency_hz == 0.0) {
    start.dynamics_frequency_hz = found.dynamics_frequency_hz;
    start.dynamics_damping = found.dynamics_damping;
  }
  if (start.dynamics2_frequency_hz == 0.0) {
    start.dynamics2_frequency_hz = found.dynamics2_frequency_hz;
    start.dynamics2_damping = found.dynamics2_damping;
  }
}

// Where the accepted correction has two modes or a direct path, its dynamics block.
void keep_named_modes(SearchState& st) {
  const ChannelCorrection& c = st.accepted;
  if (c.dynamics2_frequency_hz == 0.0 && c.dynamics_direct == 0.0) return;
  ChannelCorrection block;
  block.dynamics_frequency_hz = c.dynamics_frequency_hz;
  block.dynamics_damping = c.dynamics_damping;
  block.dynamics_direct = c.dynamics_direct;
  block.dynamics2_frequency_hz = c.dynamics2_frequency_hz;
  block.dynamics2_damping = c.dynamics2_damping;
  block.dynamics2_share = c.dynamics2_share;
  st.named_modes = block;
}

}  // namespace

void search_rounds(const SearchInput& in, SearchState& st, std::vector<Finding>& findings) {
  for (std::size_t round = 0; round < in.options.max_effects && st.current_sse > 0.0; ++round) {
    struct Tried {
      const Candidate* candidate;
      identification::CorrectionFit fit;
      double explains;
      BlockShares blocks;  // over the held-out blocks
      HoldJudgement holds;
      std::vector<CorrectionTerm> terms;
      ChannelCorrection start;
      bool levels_judged;  // on held-out holds (hysteresis operators, when needed)
      bool in_pool{false};
    };
    std::vector<Tried> tried;
    // What any candidate must explain to be named: min_explains of what is left, min_share of
    // what the model left.
    const auto large_enough = [&](const Tried& t) {
      return t.explains >= in.options.min_explains &&
             t.explains * st.current_sse >= in.options.min_share * st.original_sse;
    };
    for (const Candidate& c : candidates()) {
      if (named_already(st.used, c)) continue;
      if (!applicable(c, in.ch, in.s, in.has_sensor, in.charge_drive)) continue;
      const std::vector<CorrectionTerm> terms = merged(st.accepted_terms, c.terms);
      ChannelCorrection start = st.accepted;
      ChannelCorrection seed;  // filters chosen before this candidate's own search
      if (c.extends_previous) {
        // Tried where the candidate before it (its simpler form) is significant on the held-out
        // blocks this round and its fit is extensible(), with that candidate's filters kept.
        const Candidate* simpler = &c - 1;
        const auto previous = std::find_if(tried.begin(), tried.end(),
                                           [&](const Tried& t) { return t.candidate == simpler; });
        if (previous == tried.end() || !large_enough(*previous) ||
            !passes_blocks(previous->blocks, in.options) || !extensible(previous->fit.correction)) {
          continue;
        }
        take_filters(seed, previous->fit.correction);
        take_filters(start, seed);
      }
      try {
        if (searches_filter(c, start) && !st.accepted_terms.empty()) {
          // Search the new filter's parameters on what the st.accepted terms leave (few columns),
          // then refit every coefficient jointly with the filters fixed.
          identification::CorrectionSignals on_current = in.cs;
          on_current.y = st.current;
          const ChannelCorrection found =
              identification::fit_correction(on_current, c.terms, seed, in.rows.fit).correction;
          take_filters(start, found);
        }
        identification::CorrectionFit fit =
            identification::fit_correction(in.cs, terms, start, in.rows.fit);
        // A correction that must rescale the model's own output by more than 100 % is a
        // different model, not physics the model left out (re-identify instead).
        if (std::abs(fit.correction.gain) > in.options.max_gain) continue;
        if (is_creep(c) && !creep_moves_with_the_step(fit.correction)) continue;
        const double sse = sse_over(in.ch.recorded, fit.output, in.rows.judge);
        const double explains = 1.0 - sse / st.current_sse;
        const BlockShares shares = block_explains(in.ch.recorded, st.current, fit.output, in.rows);
        HoldJudgement holds;
        if (is_creep(c) && explains >= in.options.min_explains &&
            !passes_blocks(shares, in.options)) {
          holds = judge_on_holds(in.cs, terms, start, in.rows, st.current, in.holds,
                                 HoldMeasure::kMovement, in.options);
        }
        tried.push_back({&c, std::move(fit), explains, shares, holds, terms, start, false});
      } catch (const std::invalid_argument&) {
        continue;  // no finite fit of this candidate on these signals: not a candidate here
      }
    }
    if (tried.empty()) break;
    if (round == 0) {
      double mode_explains = -std::numeric_limits<double>::infinity();
      const auto leader =
          std::max_element(tried.begin(), tried.end(),
                           [](const Tried& a, const Tried& b) { return a.explains < b.explains; });
      st.stress_leads = std::string_view(leader->candidate->effect) == "stress_dependence" &&
                        leader->explains > 0.0;
      for (const Tried& t : tried) {
        const bool mode = uses_term(*t.candidate, CorrectionTerm::kDynamics);
        if (mode || uses_term(*t.candidate, CorrectionTerm::kDelay)) {
          st.lag_explains = std::max(st.lag_explains, t.explains);
        }
        if (mode && t.explains > mode_explains) {
          mode_explains = t.explains;
          st.lag_mode.dynamics_frequency_hz = t.fit.correction.dynamics_frequency_hz;
          st.lag_mode.dynamics_damping = t.fit.correction.dynamics_damping;
        }
      }
    }
    std::sort(tried.begin(), tried.end(),
              [](const Tried& a, const Tried& b) { return a.explains > b.explains; });
    // The held-out holds judge a hysteresis operator only when it would be named or listed
    // (each judgement costs a fit).
    const auto significant = [&](Tried& t) {
      if (!large_enough(t)) return false;
      const bool in_blocks = passes_blocks(t.blocks, in.options);
      if (!t.candidate->generic) return in_blocks || creep_passes_on_holds(t.holds, in.options);
      if (!in_blocks) return false;
      if (!t.levels_judged) {
        t.levels_judged = true;
        t.holds = judge_on_holds(in.cs, t.terms, t.start, in.rows, st.current, in.holds,
                                 HoldMeasure::kLevel, in.options);
      }
      return harmless_on_holds(t.holds, in.options);
    };
    // Specific physics first: when one is significant, a generic candidate competes only if
    // it leaves clearly less (a loop the specific terms merely resemble); otherwise it is an
    // alternative and may explain what is left in a later round.
    double specific_left = std::numeric_limits<double>::infinity();
    for (Tried& t : tried) {
      if (!t.candidate->generic && significant(t)) {
        specific_left = std::min(specific_left, 1.0 - t.explains);
      }
    }
    const auto competes = [&](const Tried& t) {
      return !t.candidate->generic || 1.0 - t.explains <= in.options.generic_ratio * specific_left;
    };
    // The pool: candidates that compete and are significant, best first (a generic candidate
    // that fails on the held-out holds leaves the others their chance).
    for (Tried& t : tried)
      t.in_pool = competes(t) && significant(t);
    const auto pool =
        static_cast<std::size_t>(std::stable_partition(tried.begin(), tried.end(),
                                                       [](const Tried& t) { return t.in_pool; }) -
                                 tried.begin());
    if (pool == 0) break;
    // Of the candidates explaining about as much as the best, the simplest.
    std::size_t chosen = 0;
    for (std::size_t i = 1; i < pool; ++i) {
      if (1.0 - tried[i].explains <= in.options.parsimony_ratio * (1.0 - tried.front().explains) &&
          complexity(tried[i].candidate->terms) < complexity(tried[chosen].candidate->terms)) {
        chosen = i;
      }
    }
    std::swap(tried[0], tried[chosen]);
    Tried& best = tried.front();

    Finding f;
    f.effect = best.candidate->effect;
    f.channel = in.ch.name;
    // Contract: the share of the channel's residual variance (held-out blocks) this physics
    // removes, so the shares of several findings add up.
    f.explains = st.original_sse > 0.0 ? best.explains * st.current_sse / st.original_sse : 0.0;
    for (std::size_t i = 1; i < tried.size(); ++i) {
      // Another form of the same effect is not an alternative (the finding names it anyway).
      if (tried[i].explains >= in.options.alternative_share * best.explains &&
          std::string_view(tried[i].candidate->effect) != std::string_view(f.effect) &&
          significant(tried[i])) {
        Finding other;
        other.effect = tried[i].candidate->effect;
        other.explains =
            st.original_sse > 0.0 ? tried[i].explains * st.current_sse / st.original_sse : 0.0;
        describe(other, *tried[i].candidate, tried[i].fit.correction, in.ch, in.s, st.current,
                 tried[i].fit.output, judged_on(tried[i].holds, in.options));
        f.alternatives.push_back({other.effect, other.explains, std::move(other.evidence)});
      }
    }
    const std::size_t n = st.current.size();
    std::vector<double> change(n);
    for (std::size_t k = 0; k < n; ++k)
      change[k] = best.fit.output[k] - st.current[k];
    f.where = large_segments(change, 1.5, 5);
    if (f.where.empty()) f.where = {{0, n}};  // spread evenly: the whole record
    const std::string judged = judged_on(best.holds, in.options);
    describe(f, *best.candidate, best.fit.correction, in.ch, in.s, st.current, best.fit.output,
             judged);
    findings.push_back(std::move(f));

    st.accepted_terms = merged(st.accepted_terms, best.candidate->terms);
    st.accepted = best.fit.correction;
    keep_named_modes(st);
    st.used.push_back(best.candidate);
    ++st.rounds_named;
    st.current = best.fit.output;
    st.current_sse = sse_over(in.ch.recorded, st.current, in.rows.judge);
  }
}

void local_pass(const SearchInput& in, SearchState& st, std::vector<Finding>& findings) {
  constexpr double kLocalEvidence = 20.0;
  const std::size_t n = st.current.size();
  std::vector<double> residual(n);
  for (std::size_t k = 0; k < n; ++k)
    residual[k] = in.ch.recorded[k] - st.current[k];
  for (const Segment& seg : large_segments(residual, 3.0, 3)) {
    const bool known = std::any_of(findings.begin(), findings.end(), [&](const Finding& f) {
      return f.channel == in.ch.name &&
             std::any_of(f.where.begin(), f.where.end(),
                         [&](const Segment& w) { return overlaps(w, seg); });
    });
    const auto seg_n = static_cast<double>(seg.end - seg.begin);
    const double before = segment_sse(in.ch.recorded, st.current, seg);
    if (known || seg_n < 16.0 || !(before > 0.0)) continue;
    std::vector<bool> in_segment(n, false);
    for (std::size_t k = seg.begin; k < seg.end; ++k) {
      in_segment[k] = in.rows.fit[k] || in.rows.judge[k];
    }
    identification::CorrectionSignals on_current = in.cs;
    on_current.y = st.current;
    const Candidate* best = nullptr;
    ChannelCorrection best_found;
    double best_bic = -kLocalEvidence;
    // The simpler form a richer one displaced as the best: named instead where the richer one
    // does not hold over the whole record.
    const Candidate* simpler = nullptr;
    ChannelCorrection simpler_found;
    double simpler_bic = 0.0;
    for (const Candidate& c : candidates()) {
      if (named_already(st.used, c)) continue;
      if (!applicable(c, in.ch, in.s, in.has_sensor, in.charge_drive)) continue;
      // A hysteresis operator fitted to one stretch would bend to anything in it: transients
      // are named by specific physics only.
      if (c.generic) continue;
      // A richer form only beside its simpler one where that is the best so far, from its
      // filters (the information criterion then weighs the parameters it adds).
      ChannelCorrection seed;
      if (c.extends_previous) {
        if (best != &c - 1 || !extensible(best_found)) continue;
        take_filters(seed, best_found);
      }
      identification::CorrectionFit local;
      try {
        local = identification::fit_correction(on_current, c.terms, seed, in_segment);
      } catch (const std::invalid_argument&) {
        continue;  // no finite fit in this stretch
      }
      if (is_creep(c) && !creep_moves_with_the_step(local.correction)) continue;
      const double after = segment_sse(in.ch.recorded, local.output, seg);
      const double bic = seg_n * std::log(std::max(after, 1e-300) / before) +
                         static_cast<double>(complexity(c.terms)) * std::log(seg_n);
      if (after <= 0.5 * before && bic < best_bic) {
        if (c.extends_previous) {
          simpler = best;
          simpler_found = best_found;
          simpler_bic = best_bic;
        }
        best_bic = bic;
        best = &c;
        best_found = local.correction;
      }
    }
    if (best == nullptr) continue;
    const double held_before = sse_over(in.ch.recorded, st.current, in.rows.judge);
    // Every coefficient refitted over the whole record with the stretch's filters; named where
    // that does not lose on the held-out blocks and keeps the stretch's gain.
    const auto joint_fit =
        [&](const Candidate& chosen, const ChannelCorrection& found,
            std::vector<CorrectionTerm>& terms) -> std::optional<identification::CorrectionFit> {
      ChannelCorrection start = st.accepted;
      take_filters(start, found);
      terms = merged(st.accepted_terms, chosen.terms);
      try {
        identification::CorrectionFit joint =
            identification::fit_correction(in.cs, terms, start, in.rows.fit);
        const double held_after = sse_over(in.ch.recorded, joint.output, in.rows.judge);
        const double seg_after = segment_sse(in.ch.recorded, joint.output, seg);
        if (held_after > 1.02 * held_before || seg_after > 0.5 * before) return std::nullopt;
        return joint;
      } catch (const std::invalid_argument&) {
        return std::nullopt;
      }
    };
    std::vector<CorrectionTerm> terms;
    std::optional<identification::CorrectionFit> held = joint_fit(*best, best_found, terms);
    if (!held && simpler != nullptr) {
      best = simpler;
      best_bic = simpler_bic;
      held = joint_fit(*best, simpler_found, terms);
    }
    if (!held) continue;
    const identification::CorrectionFit& joint = *held;
    const double held_after = sse_over(in.ch.recorded, joint.output, in.rows.judge);
    const double seg_after = segment_sse(in.ch.recorded, joint.output, seg);
    Finding f;
    f.effect = best->effect;
    f.channel = in.ch.name;
    // Contract: the share of the channel's residual variance (held-out blocks) it removes; the
    // share within its stretch goes into the evidence.
    f.explains =
        st.original_sse > 0.0 ? std::max(0.0, held_before - held_after) / st.original_sse : 0.0;
    f.where = {seg};
    const std::string judged =
        format("in the one stretch of %.3g s that shows it (%.0f %% there; BIC %.3g)",
               seg_n * in.s.sample_time, 100.0 * (1.0 - seg_after / before), best_bic);
    describe(f, *best, joint.correction, in.ch, in.s, st.current, joint.output, judged);
    findings.push_back(std::move(f));
    st.used.push_back(best);
    st.accepted_terms = terms;
    st.accepted = joint.correction;
    keep_named_modes(st);
    st.current = joint.output;
    st.current_sse = sse_over(in.ch.recorded, st.current, in.rows.judge);
  }
}

void absorbed_pass(const SearchInput& in, SearchState& st, std::vector<Finding>& findings) {
  const bool named = std::any_of(findings.begin(), findings.end(),
                                 [&](const Finding& f) { return f.channel == in.ch.name; });
  if (named || !(st.current_sse > 0.0)) return;
  // The model's own loop, refitted beside each candidate: gain, offset and a PI operator of the
  // drive (the span of a hysteresis model's weights).
  const std::vector<CorrectionTerm> own{CorrectionTerm::kOffset, CorrectionTerm::kHysteresis};
  identification::CorrectionFit refit;
  try {
    refit = identification::fit_correction(in.cs, own, ChannelCorrection{}, in.rows.fit);
  } catch (const std::invalid_argument&) {
    return;
  }
  const double refit_sse = sse_over(in.ch.recorded, refit.output, in.rows.judge);
  if (!(refit_sse > 0.0)) return;
  struct Passed {
    const Candidate* candidate;
    identification::CorrectionFit fit;
    std::vector<CorrectionTerm> terms;
    ChannelCorrection start;
    double explains;  // of the refit's held-out residual
    double sse;
  };
  std::vector<Passed> passed;
  for (const Candidate& c : candidates()) {
    // Each in its simplest form: a richer one is tried in the rounds, beside its simpler one.
    if (c.generic || c.extends_previous) continue;
    if (!applicable(c, in.ch, in.s, in.has_sensor, in.charge_drive)) continue;
    std::vector<CorrectionTerm> terms = merged(own, c.terms);
    try {
      ChannelCorrection start;
      if (searches_filter(c, start)) {
        // The filter's parameters on what the refit leaves, then every coefficient jointly.
        identification::CorrectionSignals on_refit = in.cs;
        on_refit.y = refit.output;
        start = identification::fit_correction(on_refit, c.terms, ChannelCorrection{}, in.rows.fit)
                    .correction;
      }
      identification::CorrectionFit fit =
          identification::fit_correction(in.cs, terms, start, in.rows.fit);
      if (std::abs(fit.correction.gain) > in.options.max_gain) continue;
      if (is_creep(c) && !creep_moves_with_the_step(fit.correction)) continue;
      const double sse = sse_over(in.ch.recorded, fit.output, in.rows.judge);
      const double explains = 1.0 - sse / refit_sse;
      // Significant against the refit alone, and better than the model as it stands.
      if (explains < in.options.min_explains || sse >= st.current_sse ||
          (st.current_sse - sse) < in.options.min_share * st.original_sse ||
          !passes_blocks(block_explains(in.ch.recorded, refit.output, fit.output, in.rows),
                         in.options)) {
        continue;
      }
      passed.push_back({&c, std::move(fit), std::move(terms), start, explains, sse});
    } catch (const std::invalid_argument&) {
      continue;  // no finite fit of this candidate on these signals
    }
  }
  std::sort(passed.begin(), passed.end(),
            [](const Passed& a, const Passed& b) { return a.explains > b.explains; });
  // The refitted loop can draw each hold's level from the other half of the same hold: like a
  // generic candidate, it must do no harm on held-out holds.
  const auto harmless = [&](const Passed& p) {
    return in.holds.empty() ||
           harmless_on_holds(judge_on_holds(in.cs, p.terms, p.start, in.rows, st.current, in.holds,
                                            HoldMeasure::kLevel, in.options, own),
                             in.options);
  };
  const auto chosen = std::find_if(passed.begin(), passed.end(), harmless);
  if (chosen == passed.end()) return;
  Passed& best = *chosen;
  Finding f;
  f.effect = best.candidate->effect;
  f.channel = in.ch.name;
  f.explains = st.original_sse > 0.0 ? (st.current_sse - best.sse) / st.original_sse : 0.0;
  const std::size_t n = st.current.size();
  std::vector<double> change(n);
  for (std::size_t k = 0; k < n; ++k)
    change[k] = best.fit.output[k] - st.current[k];
  f.where = large_segments(change, 1.5, 5);
  if (f.where.empty()) f.where = {{0, n}};
  const std::string judged = format(
      "on held-out blocks, fitted beside a refit of the model's own loop (the model had absorbed "
      "part of it; against that refit alone it removes %.0f %%)",
      100.0 * best.explains);
  describe(f, *best.candidate, best.fit.correction, in.ch, in.s, st.current, best.fit.output,
           judged);
  findings.push_back(std::move(f));
  st.used.push_back(best.candidate);
  st.accepted_terms = best.terms;
  st.accepted = best.fit.correction;
  st.current = best.fit.output;
  st.current_sse = best.sse;
}

}  // namespace selfsense::diagnosis::detail
