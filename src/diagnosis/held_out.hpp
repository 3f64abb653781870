// Held-out judgement of a candidate (docs/diagnose.md, "Decisions"): which samples fit and which
// judge, the signed-rank test over held-out blocks, and held-out holds (each hold predicted by a
// fit without it). Pure math.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "selfsense/diagnosis/diagnosis.hpp"
#include "selfsense/diagnosis/residual_tests.hpp"
#include "selfsense/diagnosis/statistics.hpp"
#include "selfsense/identification/correction_fit.hpp"

namespace selfsense::diagnosis::detail {

// Which samples fit and which judge: sample k lies in block (k blocks) / n; even blocks fit,
// odd ones judge. Samples where the model gave no finite output do neither.
struct Rows {
  std::vector<bool> fit{};
  std::vector<bool> judge{};
  std::vector<std::size_t> block{};
  std::size_t blocks{0};
};
[[nodiscard]] Rows make_rows(const std::vector<bool>& usable, std::size_t blocks);

// Per held-out block, the residual's energy before and after a candidate: the signed-rank test
// over the blocks (statistics.hpp) says whether its gain is significant, the worst block whether
// it makes some stretch worse (a term that does will not carry over to new data either).
struct BlockShares {
  GainTest test{};
  double worst{0.0};     // the largest loss of one block, relative to max(its own, the mean block)
  double explains{0.0};  // 1 - sum after / sum before over the judged blocks
};
[[nodiscard]] BlockShares block_explains(std::span<const double> recorded,
                                         const std::vector<double>& before,
                                         const std::vector<double>& after, const Rows& rows);

// The block test: a significant gain over the held-out blocks, and none worse by more than the
// larger of `max_block_loss` and the share the candidate removes over all of them together
// (shares.explains): a strong effect may leave one stretch as much worse as it makes the
// record better on average, a weak one no more than max_block_loss.
[[nodiscard]] bool passes_blocks(const BlockShares& shares, const Options& options);

// Sum of squared errors over the marked rows, and over a segment.
[[nodiscard]] double sse_over(std::span<const double> recorded, const std::vector<double>& model,
                              const std::vector<bool>& rows);
[[nodiscard]] double segment_sse(std::span<const double> recorded, const std::vector<double>& model,
                                 const Segment& seg);
[[nodiscard]] bool overlaps(const Segment& a, const Segment& b);

// Held-out holds. Alternate time blocks cut each hold in two, so on a record of steps and holds a
// term that draws each hold's level from the other half of the same hold passes them without
// predicting anything new. Holding out whole holds (holds i, i + G, ... together, G <= 8 folds;
// the candidate refitted on everything else, identification::held_out_outputs) judges what it
// predicts for a hold it never saw.
//  - Creep lives in the holds after steps; in a record of a few holds that differ (large steps
//    and small ones, switching and none) the blocks judge it where it barely shows. It may pass on
//    the holds instead: judged on how the residual moves within each held-out hold (the hold's
//    mean removed: creep is the movement, the level is the static loop's), it must explain at
//    least `min_explains` of that movement over all holds and in two holds or more (not one by
//    chance).
//  - A hysteresis operator (generic: it can draw any level) must also do no harm there: the
//    residual over the held-out holds no larger than before.
// The baseline is `current`, or with `baseline_terms` those terms fitted without each hold too
// (a fair comparison when the candidate carries them).
// Either way no hold may get worse by more than `max_block_loss` of the larger of its own and
// the mean hold's residual (a hold that hardly moves is judged against the others, not against
// its own noise).
enum class HoldMeasure : std::uint8_t { kMovement, kLevel };

struct HoldJudgement {
  bool judged{false};
  HoldMeasure measure{HoldMeasure::kMovement};
  double explains{0.0};  // of the residual (or its movement) over the held-out holds
  double worst{0.0};     // the largest relative loss in one hold
  std::size_t improved{0};
  std::size_t holds{0};
};

[[nodiscard]] HoldJudgement judge_on_holds(
    const identification::CorrectionSignals& cs,
    const std::vector<identification::CorrectionTerm>& terms,
    const models::ChannelCorrection& start, const Rows& rows, const std::vector<double>& current,
    const std::vector<Segment>& holds, HoldMeasure measure, const Options& options,
    const std::vector<identification::CorrectionTerm>& baseline_terms = {});

// Creep named on the holds (HoldMeasure::kMovement).
[[nodiscard]] bool creep_passes_on_holds(const HoldJudgement& j, const Options& options);

// A hysteresis operator's levels on the holds (HoldMeasure::kLevel).
[[nodiscard]] bool harmless_on_holds(const HoldJudgement& j, const Options& options);

// How a finding was judged, for its evidence.
[[nodiscard]] std::string judged_on(const HoldJudgement& holds, const Options& options);

}  // namespace selfsense::diagnosis::detail
