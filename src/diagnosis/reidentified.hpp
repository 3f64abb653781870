// Charge leakage judged by re-identifying the model with the leak undone (docs/diagnose.md,
// "Re-identified with the effect undone"). Pure math.
//
// A leak acts on the measured charge after everything the model draws: the charge amplifier's
// feedback resistance forgets it (a high-pass, tau), the stack's parallel conductance adds the
// field's integral (sigma q). A base identified on a recording with the leak bends its own slow
// creep operators to imitate it over that record; its residual then holds little of the leak,
// and no correction added after the model wins it back. The question becomes which structure
// forecasts better, so each form is judged by the model's own identification:
//   1. the record splits in two halves; the first identifies, the second judges, cut into as
//      many blocks as the diagnosis has (a leak keeps integrating where creep settles: a
//      forecast shows it, alternate blocks of one record do not);
//   2. null: the model's structure identified on the first half of D as recorded;
//   3. each leak theta (high-pass tau, or conductance sigma of either sign, on a grid): the
//      structure identified on the first half of D with the leak undone (the correction
//      stage's inverse), its prediction over the whole record mapped back through the leak;
//      theta chosen by the first half's error alone;
//   4. named when the first half's fit with the leak undone leaves at most 1 - min_explains of
//      the null's error there (the identification's own evidence), and on the judging blocks
//      it beats the null by the diagnosis's rules
//      (statistics.hpp: the signed-rank test at kConfidence, min_explains of the null's error,
//      no block worse by more than max_block_loss); the improved model is the structure
//      identified on the whole record with the leak undone, with the leak as its correction.
// Only the sensor side of field-drive models with one side per channel (not vectorial).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "candidates.hpp"
#include "channel_data.hpp"
#include "held_out.hpp"
#include "selfsense/diagnosis/diagnosis.hpp"
#include "selfsense/identification/transducer_fit.hpp"

namespace selfsense::diagnosis::detail {

// An effect judged by re-identification: the channel's side identified with it undone.
struct Reidentified {
  Finding finding{};
  models::SideModel side{};                           // identified with the effect undone
  models::ChannelCorrection correction{};             // the effect
  std::vector<identification::CorrectionTerm> terms;  // its terms
  const Candidate* candidate{nullptr};                // its candidate (named once per channel)
  std::vector<double> base{};                         // the re-identified side's output
  std::vector<double> output{};                       // ... through the effect
  // The share of the null's error it removes on the half it was identified on (finding.explains:
  // on the half it forecast); judged by a forecast only.
  double fit_explains{0.0};
  // The structure the side was identified with, when it is not the model's (creep operators
  // added to a hysteresis model).
  std::optional<models::Structure> structure{};
  // Not judged against the null: a side to carry an effect the rounds named (with their finding),
  // or a delay in the place of a mode they named (a finding of its own, which the caller
  // describes once it has weighed the side: until then its evidence says what chose the form).
  bool carried{false};
};

// Rows of a forecast: the first `half` samples fit, the rest judges in `judging` blocks (the odd
// block numbers block_explains reads). No block fits between them, so the whole second half
// judges: the diagnosis's block count there. Rows where a or b is not finite are left out.
[[nodiscard]] Rows forecast_rows(std::size_t n, std::size_t half, std::size_t judging,
                                 const std::vector<double>& a, const std::vector<double>& b);

// The same for a backcast: the samples from `half` on fit, the first `half` judge.
[[nodiscard]] Rows backcast_rows(std::size_t n, std::size_t half, std::size_t judging,
                                 const std::vector<double>& a, const std::vector<double>& b);

// Where a re-identified model's output departs most from the current one (the whole record when
// the change is spread evenly): a finding's located segments.
[[nodiscard]] std::vector<Segment> where_it_changes(const std::vector<double>& output,
                                                    const std::vector<double>& current);

// What a re-identified effect must show: the identification's own evidence (the first half
// fitted by min_explains better) and the forecast, or the forecast alone. Beside a creep
// structure the fit cannot show a slow leak: over the half it is fitted on, the slowest lags
// integrate like the leak and take it in; past it the lags settle and the leak keeps
// integrating, which only the forecast sees. Where kFitAndForecast's fit falls short, the
// effect may show on held-out data both ways instead: the forecast, and the backcast of the
// first half by the side identified on the second (docs/diagnose.md, "Shown both ways").
enum class ShownBy : std::uint8_t { kFitAndForecast, kForecast };

// The best form of leak when it is significant; nullopt otherwise (or when the model or the
// recording does not allow the test).
[[nodiscard]] std::optional<Reidentified> reidentified_leak(
    const models::TransducerModel& model, const Signals& s, const ChannelData& ch,
    const std::vector<double>& current, const Options& options,
    ShownBy evidence = ShownBy::kFitAndForecast);

// Creep judged the same way where the model has no creep operators (a `hysteresis` model): a
// loop identified on a creeping stack bends to the creep, and lags added after it carry little
// to new excitation. The null is the model's structure identified on the first half, the
// candidate the same with creep operators (hysteresis-creep); the improved model carries that
// side (the model's structure becomes hysteresis-creep, the other side unchanged, its creep
// operators none). With `beside` (a leak already re-identified on the channel), both structures
// are identified with it undone and forecast through it, and the improved model carries it as
// its correction.
[[nodiscard]] std::optional<Reidentified> reidentified_creep(
    const models::TransducerModel& model, const Signals& s, const ChannelData& ch,
    const std::vector<double>& current, const Options& options,
    const models::ChannelCorrection& beside = {});

// Creep and a leak on the sensed channel judged as one forecast, where neither alone was named:
// each alone leaves the other's drift to extrapolate (a creep structure fitted beside an
// unmodelled leak bends its slowest lags to it, a leak fitted beside unmodelled creep takes the
// creep's settling in), so each forecast fails though the pair would not. The candidate is the
// structure with creep operators identified on the first half with each leak of reidentified_leak's
// grid undone (the leak chosen on that half's fit). It must beat the null (the model's structure,
// no leak) as reidentified_creep's candidate does, and each part must carry the forecast: the
// pair beats the creep structure alone and the model's structure with its own best leak by
// forecast_explains (ShownBy::kForecast). `reidentified` carries the creep finding, the side,
// and the leak as its correction (its candidate and terms the leak's); `leak` is the leak's
// finding.
struct CreepAndLeak {
  Reidentified reidentified{};
  Finding leak{};
};

[[nodiscard]] std::optional<CreepAndLeak> reidentified_creep_and_leak(
    const models::TransducerModel& model, const Signals& s, const ChannelData& ch,
    const std::vector<double>& current, const Options& options);

// Stress dependence judged by re-identification with the stress-hysteresis structure
// (docs/diagnose.md, "Stress dependence re-identified"): a stack whose permittivity, coupling
// and loop size move with the stress bends an affine base to it, and no correction after it
// carries to new loads. The null is the model's structure identified on the first half of both
// channels, the candidate `stress-hysteresis` (D or S = W0.q + T W1.q + d1 T + d2 T^2, the plays
// of the field: loop and permittivity scaled by T, coupling quadratic in T) identified there too
// (and each on the second half, forecasting the first); each channel it forecasts better by the
// rules of a round, the halves the unit of harm, is named where the structure identified on the
// whole record also fits it by min_explains better than the given model (below). A
// channel it forecasts worse keeps the model's own side (the plain side's dead zones and creep
// can fit a channel without the effect better than the structure's plays), the others take the
// structure's (models/stress_sides.hpp). The improved model is that structure identified on the
// whole record, completed by the kept side. Nothing is judged where the stress does not move
// apart from the field (a constant preload: what a fit on E and the base's outputs leaves of T is
// below 1e-9 of its magnitude), and nothing is returned where the structure identified on the
// whole record fits a channel worse than the given model; a named channel it fits by less than
// min_explains better is no longer named (the others stay).
// diagnose() calls it only where its first pass named nothing or nothing but stress, and takes
// it only where it names a channel that pass did not.
struct StressReidentified {
  models::TransducerModel model{};  // stress-hysteresis, identified on the whole record
  Outputs outputs{};                // its D and S over the record
  std::vector<Finding> named{};     // one per channel where the forecast wins
  std::vector<std::string> kept{};  // channels that keep the model's own side

  [[nodiscard]] bool replaces(const std::string& channel) const {
    return std::find(kept.begin(), kept.end(), channel) == kept.end();
  }
};

[[nodiscard]] std::optional<StressReidentified> reidentified_stress(
    const models::TransducerModel& model, const Signals& s,
    const std::vector<ChannelData>& channels, const Options& options);

// The structure's side of the channel identified on the first half of the recording as recorded
// (the model's state at the start searched for): identified once per structure and channel
// (ChannelData::first_half). Throws std::invalid_argument where no identification exists.
[[nodiscard]] models::TransducerModel first_half_fit(models::Structure structure, const Signals& s,
                                                     const ChannelData& ch);

// The options of every identification a judgement runs: the structure's defaults, with each
// least-squares fit over at most kReidentifiedRows samples (IdentificationOptions::max_rows:
// every m-th of a longer record). A judgement compares forecasts whose residual is model error
// far above the fit's own noise; with at most ~100 parameters per side, 2e5 rows leave the
// parameters' estimation variance below p / rows = 5e-4 of the residual's, and a 1e6-sample
// record's halves cost a third (docs/diagnose.md, "Speed"). Records up to 2e5 samples (the
// independent draws', every test's) are fitted on every sample as before.
inline constexpr std::size_t kReidentifiedRows = 200000;
[[nodiscard]] identification::IdentificationOptions reidentification_options(
    models::Structure structure);

// The first candidate that carries `term`.
[[nodiscard]] const Candidate& candidate_using(identification::CorrectionTerm term);

// A lag: a delay on either channel judged the same way (docs/diagnose.md, "Delay
// re-identified"): a base identified on a channel sampled late bends its fastest creep lags to
// the lag, and a delay fitted after it then doubles what they already imitate where the drive
// is slow. The channel is read that much later (the delay undone) for the identification; the
// delay is chosen on the first half's fit over a quarter of a sample to 16 samples and judged as
// a forecast like the leak. On S, with `mode_seed` (the mode the rounds fitted: its frequency
// and damping), the modes around it are identified the same way (the mode undone by
// mode_undone.hpp); the best replaces the delay where the delay's first-half residual is more
// than `parsimony_ratio` times the mode's (the rounds' rule for the simpler of two candidates:
// the mode has one parameter more), and the finding is then `dynamics`.
//
// Where the rounds saw no lag (LagSeen::kNo: no delay or mode explained min_explains in the
// first round), the base may have taken a lag of several samples in as loop width, which the
// first half's fit shows plainly once the lag is undone. There the delays are tried from the
// shortest up until the fit has worsened twice in a row, and the lag is judged only where the
// best fits the first half by min_explains better than the null (no backcast in its place, no
// refinement or mode before that): a few identifications on a channel with no lag.
//
// With `named_lag` a delay the rounds named and nothing else on the channel, a delay that is
// not judged against the null still comes back, carried (Reidentified::carried, with the rounds'
// finding): the side identified on the whole record with the delay undone. The caller keeps it
// where it fits the record better than the rounds' delay after the model: both are the side and
// one delay, and the joint fit is not biased by the part of the delay the side took in (the
// rounds read the sub-sample delays on D of 900003, 900006, 900017 and 900027 17-34 % short;
// docs/diagnose.md, "A delay the rounds named, carried by the side identified with it").
// Where `named_lag` is a mode named alone on S (by the rounds or the local pass, in one stretch),
// the delay is carried in its place (a finding of its own) where it is the simpler form of the
// same lag: the delay chosen over the modes by the first half's fit (parsimony_ratio, above) and
// its forecast of the second half no worse than the best mode's (both on the rows where both
// forecasts are finite); its finding is then the caller's to describe (and to refuse where the
// side fits the record, or the mode's stretches, worse than the mode after the model). The
// signed-rank test of the forecast blocks needs no pass here: the lag was named already, and only
// its form is chosen (a delay shows at the fast moves only, so on the slow blocks of a forecast the
// sign of the change is noise: 900008's delay forecast 71 % better at p = 0.038).
enum class LagSeen { kInRounds, kNo };

[[nodiscard]] std::optional<Reidentified> reidentified_lag(
    const models::TransducerModel& model, const Signals& s, const ChannelData& ch,
    const std::vector<double>& current, const Options& options,
    const models::ChannelCorrection& mode_seed = {}, LagSeen seen = LagSeen::kInRounds,
    const models::ChannelCorrection& named_modes = {}, const Finding* named_lag = nullptr);

}  // namespace selfsense::diagnosis::detail

namespace selfsense::diagnosis::detail {

// Temperature dependence judged by re-identification too (docs/diagnose.md, "Temperature
// re-identified"): a base identified on a recording whose stack warmed has bent its creep and
// loop to the drift, so a correction fitted to its residual learns the bend and carries nothing
// to new data. The channel's side and the temperature's terms are identified together,
// alternating three times: the terms fitted on the fitting blocks to the side's residual, the
// side identified on the whole record with the terms undone (they are affine in the model's
// output per sample). Null: the side identified on the record as it is. Both sides saw every
// block; only the terms' few coefficients did not see the held-out ones, where the joint model
// must beat the null by the rules of a round (signed-rank test at kConfidence, min_explains, no
// block worse by more than max_block_loss). A forecast of the second half (as for the leak) was
// tried first: a ramp then extrapolates past the temperatures the first half saw. The quadratic
// terms replace the linear ones where they beat them on the held-out blocks (test and block
// rule, no effect size: a nested model). Field-drive models with one side per channel; the
// recording's temperature must move by more than 1 K.
// Where the stack stays within 30 % of the temperature's recorded range of its first sample for
// at least a fifth of the record (a ramp that starts late or slowly), the side is first
// identified on that stretch only (at least a third of the record) and the terms on the whole
// record: over the rest the side's slow creep lags would take in the drift as a slow response
// to the drive, which the alternation does not undo (the fit barely changes along that valley).
// Where that is not significant, or the stretch is shorter, the side sees the whole record.
[[nodiscard]] std::optional<Reidentified> reidentified_temperature(
    const models::TransducerModel& model, const Signals& s, const ChannelData& ch,
    const std::vector<double>& current, const Options& options);

// Stress dependence the same way: the channel's side and the stress's terms identified together
// (on D the candidate with each part of the response apart, on S the gain per pascal), judged
// and returned as reidentified_temperature does. A base identified under a moving load bends
// its loop to the stress, so the correction rounds on it win back only part of the effect.
// Field-drive models with one side per channel and a stress column.
[[nodiscard]] std::optional<Reidentified> reidentified_stress_terms(
    const models::TransducerModel& model, const Signals& s, const ChannelData& ch,
    const std::vector<double>& current, const Options& options);

}  // namespace selfsense::diagnosis::detail
