// One draw of the diagnosis proof on the independent actuator (issue 23, item 4): the effect's
// magnitude calibrated to the drawn residual ratio, a base model identified on the recording
// with the effect, the diagnosis, and the validation error before and after against the clean
// case's.
//
// For a draw (actuator.hpp, make_draw):
//   1. base structure: `hysteresis` for creep and creep_leakage, `hysteresis-creep` otherwise
//   2. the clean base: identified on the effect-free identification recording; r0_c its fit
//      nrmse on channel c (D, S)
//   3. calibration: the magnitude m such that ratio(m) = max over the affected channels c of
//      r_c(m) / r0_c equals the drawn ratio (uniform in [1.5, 5]) within 15 %, r_c(m) the fit
//      nrmse of a base identified on the identification recording with the effect at m: secant
//      steps on log m against log sqrt(ratio^2 - 1) (the effect's own share of the residual,
//      about proportional to m); creep_leakage calibrates each part alone, then both together
//   4. diagnose that base on that recording (drive E, sensed D, strain S, stress T, temp)
//   5. validation nrmse (RMS / range, docs/recording-format.md) per channel on the validation
//      recording: before (the base), after (the improved model), clean (the clean base on the
//      effect-free validation recording)
// Outcome: named_right when every expected effect word is named on its channel (the affected
// channel with the larger ratio; leakage on D), extra_names the findings that name anything
// else, the excess ratio (after - clean) / (before - clean) of the judged channel(s) (the
// largest for creep_leakage); pass = named_right, extra_names <= 1, excess <= 0.6. For `none`
// pass = no findings.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "diagnosis/independent/actuator.hpp"

namespace selfsense::independent {

struct Named {
  std::string effect{};
  std::string channel{};
  std::string evidence{};  // the finding's (empty for an expected name)
};

// Validation nrmse of one channel.
struct ChannelFigures {
  double before{0.0};
  double after{0.0};
  double clean{0.0};
};

struct Outcome {
  Draw draw{};  // with the calibrated magnitudes
  std::string structure{};
  double ratio_achieved{0.0};  // the draw's target is draw.ratio
  int calibration_steps{0};    // identifications of the calibration
  std::vector<Named> expected{};
  std::string verdict{};
  std::vector<Named> findings{};
  // The improved model's structure, with the channels whose plain side a stress-hysteresis
  // model kept: "stress-hysteresis, D plain" (models/stress_sides.hpp).
  std::string improved{};
  bool named_right{false};
  int extra_names{0};
  ChannelFigures d{};
  ChannelFigures s{};
  double excess_ratio{0.0};  // NaN when the effect does not raise the validation error
  // The improved model run by the runtime (diagnosis::simulate) on the diagnosed recording
  // against the output the diagnosis judged it by (ChannelResult::after): the nrmse between
  // the two, largest over the channels. A model that is not the one judged shows here.
  double model_gap{0.0};
  bool pass{false};
  double seconds{0.0};           // the whole draw
  double seconds_diagnose{0.0};  // ... of which the diagnosis
};

// Throws what identification and diagnosis throw.
[[nodiscard]] Outcome run_draw(std::uint64_t seed, Effect effect);

// One line: effect, form, ratio drawn and achieved, verdict, findings, validation figures, pass.
[[nodiscard]] std::string summary(const Outcome& o);

}  // namespace selfsense::independent
