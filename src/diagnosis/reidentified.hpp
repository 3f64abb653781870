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

#include <optional>
#include <vector>

#include "candidates.hpp"
#include "channel_data.hpp"
#include "selfsense/diagnosis/diagnosis.hpp"

namespace selfsense::diagnosis::detail {

struct Reidentified {
  Finding finding{};
  models::SideModel sensor{};              // identified with the leak undone
  models::ChannelCorrection correction{};  // the leak
  identification::CorrectionTerm term{};   // its term (the high-pass or the field's integral)
  const Candidate* candidate{nullptr};     // its candidate (named once per channel)
  std::vector<double> base{};              // the re-identified sensor side's D, no leak
  std::vector<double> output{};            // ... through the leak
};

// The best form of leak when it is significant; nullopt otherwise (or when the model or the
// recording does not allow the test).
[[nodiscard]] std::optional<Reidentified> reidentified_leak(const models::TransducerModel& model,
                                                            const Signals& s, const ChannelData& ch,
                                                            const std::vector<double>& current,
                                                            const Options& options);

}  // namespace selfsense::diagnosis::detail
