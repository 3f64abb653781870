#include "held_out.hpp"

#include <algorithm>
#include <limits>
#include <optional>
#include <stdexcept>

#include "text.hpp"

namespace selfsense::diagnosis::detail {

using identification::CorrectionTerm;
using models::ChannelCorrection;

Rows make_rows(const std::vector<bool>& usable, std::size_t blocks) {
  const std::size_t n = usable.size();
  Rows r;
  r.blocks = blocks;
  r.fit.resize(n);
  r.judge.resize(n);
  r.block.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    r.block[k] = (k * blocks) / n;
    r.fit[k] = usable[k] && r.block[k] % 2 == 0;
    r.judge[k] = usable[k] && r.block[k] % 2 == 1;
  }
  return r;
}

BlockShares block_explains(std::span<const double> recorded, const std::vector<double>& before,
                           const std::vector<double>& after, const Rows& rows) {
  std::vector<double> e0(rows.blocks, 0.0);
  std::vector<double> e1(rows.blocks, 0.0);
  for (std::size_t k = 0; k < recorded.size(); ++k) {
    if (!rows.judge[k]) continue;
    e0[rows.block[k]] += (recorded[k] - before[k]) * (recorded[k] - before[k]);
    e1[rows.block[k]] += (recorded[k] - after[k]) * (recorded[k] - after[k]);
  }
  std::vector<double> held0;
  std::vector<double> held1;
  BlockShares out;
  for (std::size_t b = 1; b < rows.blocks; b += 2) {
    if (!(e0[b] > 0.0)) continue;
    held0.push_back(e0[b]);
    held1.push_back(e1[b]);
  }
  // A block's loss relative to the larger of its own and the mean block's residual: a block
  // where the model is already nearly right is judged against the others, not its own noise.
  double mean = 0.0;
  for (const double e : held0)
    mean += e / static_cast<double>(held0.size());
  for (std::size_t i = 0; i < held0.size(); ++i)
    out.worst = std::min(out.worst, (held0[i] - held1[i]) / std::max(held0[i], mean));
  double sum0 = 0.0;
  double sum1 = 0.0;
  for (std::size_t i = 0; i < held0.size(); ++i) {
    sum0 += held0[i];
    sum1 += held1[i];
  }
  out.explains = sum0 > 0.0 ? 1.0 - sum1 / sum0 : 0.0;
  out.test = paired_gain_test(held0, held1);
  return out;
}

bool passes_blocks(const BlockShares& shares, const Options& options) {
  return shares.test.significant &&
         shares.worst >= -std::max(options.max_block_loss, shares.explains);
}

double sse_over(std::span<const double> recorded, const std::vector<double>& model,
                const std::vector<bool>& rows) {
  double sse = 0.0;
  for (std::size_t k = 0; k < recorded.size(); ++k) {
    if (!rows[k]) continue;
    const double e = recorded[k] - model[k];
    sse += e * e;
  }
  return sse;
}

double segment_sse(std::span<const double> recorded, const std::vector<double>& model,
                   const Segment& seg) {
  double sse = 0.0;
  for (std::size_t k = seg.begin; k < seg.end; ++k) {
    sse += (recorded[k] - model[k]) * (recorded[k] - model[k]);
  }
  return sse;
}

bool overlaps(const Segment& a, const Segment& b) {
  return a.begin < b.end && b.begin < a.end;
}

namespace {

// The output with each hold predicted by a fit without its group of holds (holds h, h + G, ...);
// nullopt when some fit has no finite solution.
std::optional<std::vector<double>> predicted_holds(const identification::CorrectionSignals& cs,
                                                   const std::vector<CorrectionTerm>& terms,
                                                   const ChannelCorrection& start, const Rows& rows,
                                                   const std::vector<double>& current,
                                                   const std::vector<Segment>& holds) {
  constexpr std::size_t kMaxFolds = 8;
  const std::size_t n = current.size();
  const std::size_t groups = std::min(holds.size(), kMaxFolds);
  std::vector<int> fold(n, -1);
  for (std::size_t h = 0; h < holds.size(); ++h) {
    for (std::size_t k = holds[h].begin; k < holds[h].end; ++k)
      fold[k] = static_cast<int>(h % groups);
  }
  std::vector<bool> usable(n);
  for (std::size_t k = 0; k < n; ++k)
    usable[k] = rows.fit[k] || rows.judge[k];
  std::vector<std::vector<double>> outputs;
  try {
    outputs = identification::held_out_outputs(cs, terms, start, usable, fold, groups);
  } catch (const std::invalid_argument&) {
    return std::nullopt;
  }
  std::vector<double> held_out(current);
  for (std::size_t h = 0; h < holds.size(); ++h) {
    const std::vector<double>& out = outputs[h % groups];
    for (std::size_t k = holds[h].begin; k < holds[h].end; ++k)
      held_out[k] = out[k];
  }
  return held_out;
}

}  // namespace

HoldJudgement judge_on_holds(const identification::CorrectionSignals& cs,
                             const std::vector<CorrectionTerm>& terms,
                             const ChannelCorrection& start, const Rows& rows,
                             const std::vector<double>& current, const std::vector<Segment>& holds,
                             HoldMeasure measure, const Options& options,
                             const std::vector<CorrectionTerm>& baseline_terms) {
  HoldJudgement j;
  j.holds = holds.size();
  if (holds.size() < 3) return j;
  j.measure = measure;
  const std::optional<std::vector<double>> held_out =
      predicted_holds(cs, terms, start, rows, current, holds);
  std::optional<std::vector<double>> baseline = current;
  if (!baseline_terms.empty()) {
    baseline = predicted_holds(cs, baseline_terms, ChannelCorrection{}, rows, current, holds);
  }
  if (!held_out || !baseline) {
    // No finite fit without some holds: the candidate cannot predict them.
    j.judged = true;
    j.explains = -std::numeric_limits<double>::infinity();
    return j;
  }
  // The residual's energy in a hold, about its mean in the hold when only movement counts.
  const auto energy = [&](const std::vector<double>& model, const Segment& h) {
    double sum = 0.0;
    double sum2 = 0.0;
    double count = 0.0;
    for (std::size_t k = h.begin; k < h.end; ++k) {
      if (!(rows.fit[k] || rows.judge[k])) continue;
      const double e = cs.recorded[k] - model[k];
      sum += e;
      sum2 += e * e;
      count += 1.0;
    }
    if (count == 0.0) return 0.0;
    return measure == HoldMeasure::kMovement ? sum2 - sum * sum / count : sum2;
  };
  std::vector<double> before(holds.size());
  std::vector<double> after(holds.size());
  double total_before = 0.0;
  double total_after = 0.0;
  for (std::size_t h = 0; h < holds.size(); ++h) {
    before[h] = energy(*baseline, holds[h]);
    after[h] = energy(*held_out, holds[h]);
    total_before += before[h];
    total_after += after[h];
  }
  if (!(total_before > 0.0)) return j;
  const double mean_before = total_before / static_cast<double>(holds.size());
  for (std::size_t h = 0; h < holds.size(); ++h) {
    if (before[h] > 0.0 && after[h] <= (1.0 - options.min_explains) * before[h]) ++j.improved;
    j.worst = std::max(j.worst, (after[h] - before[h]) / std::max(before[h], mean_before));
  }
  j.judged = true;
  j.explains = 1.0 - total_after / total_before;
  return j;
}

bool creep_passes_on_holds(const HoldJudgement& j, const Options& options) {
  return j.judged && j.measure == HoldMeasure::kMovement && j.explains >= options.min_explains &&
         j.improved >= 2 && j.worst <= options.max_block_loss;
}

bool harmless_on_holds(const HoldJudgement& j, const Options& options) {
  return !j.judged || (j.explains >= 0.0 && j.worst <= options.max_block_loss);
}

std::string judged_on(const HoldJudgement& holds, const Options& options) {
  if (!creep_passes_on_holds(holds, options)) return "on held-out blocks";
  return format(
             "on held-out blocks; judged on held-out holds, where it explains %.0f %% of the "
             "movement within them and more than %.0f %% in %.0f",
             100.0 * holds.explains, 100.0 * options.min_explains,
             static_cast<double>(holds.improved)) +
         format(" of %.0f holds", static_cast<double>(holds.holds));
}

}  // namespace selfsense::diagnosis::detail
