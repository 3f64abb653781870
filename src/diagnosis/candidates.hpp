// The candidates of a diagnosis: each effect a channel correction can add (docs/diagnose.md,
// "What each effect becomes"), as a unit that carries its terms
// (identification/correction_fit.hpp), the channels it applies to, the signals it needs, its
// parameter count (complexity of its terms) and its own description of what it found. Adding an
// effect is one entry of candidates() (candidates.cpp) and its test. Pure math.
#pragma once

#include <cstddef>
#include <cstdint>
#include <numbers>
#include <span>
#include <string>
#include <vector>

#include "channel_data.hpp"
#include "selfsense/diagnosis/diagnosis.hpp"
#include "selfsense/identification/correction_fit.hpp"

namespace selfsense::diagnosis::detail {

using identification::CorrectionTerm;
using models::ChannelCorrection;

// The damping from which a fitted mode has no resonant peak (1/sqrt(2)): in the band it is a
// delay of 2 zeta / w0 to second order, and its finding is named `delay` (describe_dynamics).
inline constexpr double kNoResonanceDamping = 1.0 / std::numbers::sqrt2;

enum class Needs : std::uint8_t { kNothing, kTemperature, kStress, kSensed, kChargeDrive };

// What a description reads: the fitted correction, the channel, the recording, the output before
// the correction, and the common tail (how much it explains, how it was judged).
struct Evidence {
  const ChannelCorrection& c;
  const ChannelData& ch;
  const Signals& s;
  const std::vector<double>& before;
  double range;  // of the recorded channel
  double pct;    // 100 / range
  std::string tail;
};
using Describe = void (*)(Finding&, const Evidence&);

struct Candidate {
  const char* effect;  // the effect's name (docs/diagnose.md)
  std::vector<CorrectionTerm> terms;
  bool on_sensed;  // the reconstruction can invert it on the sensed channel
  bool on_strain;
  Needs needs;
  // Fills the finding's evidence and its explaining feature; may name the effect more closely
  // than `effect` (a fitted mode without a resonant peak is a delay: describe_dynamics).
  Describe describe;
  // The hysteresis operators bend to many residuals (a static curve, a slow drift under a
  // periodic drive): chosen only when no specific physics explains the residual significantly.
  bool generic{false};
  // A richer form of the candidate listed just before it (two modes beside one): tried only
  // where that one's fit is extensible() and explains enough on the held-out blocks to be named
  // in the same round (on one stretch: is the best there so far), with that one's filters kept
  // (the second mode searched beside its mode); not tried by the absorbed pass.
  bool extends_previous{false};
};

[[nodiscard]] const std::vector<Candidate>& candidates();

[[nodiscard]] bool uses_term(const Candidate& c, CorrectionTerm t);
[[nodiscard]] bool is_creep(const Candidate& c);

// The candidate applies to this channel with these signals.
[[nodiscard]] bool applicable(const Candidate& c, const ChannelData& ch, const Signals& s,
                              bool has_sensed, bool charge_drive);

// Time since the drive last moved by more than 5 % of its range, log10 seconds: the feature
// creep follows.
[[nodiscard]] std::vector<double> log_time_since_step(std::span<const double> x, double ts);

// A richer form (Candidate::extends_previous) is tried beside its simpler one's fit only where
// that fit reads as the same effect: a mode without a resonant peak is a lag, named `delay`
// (describe_dynamics), and a second mode is not built on it.
[[nodiscard]] bool extensible(const ChannelCorrection& simpler_fit);

// Creep keeps moving in the direction of the last step (candidates.cpp).
[[nodiscard]] bool creep_moves_with_the_step(const ChannelCorrection& c);

// An effect is named once per channel, in whichever of its forms fitted first.
[[nodiscard]] bool named_already(const std::vector<const Candidate*>& used, const Candidate& c);

// The candidate brings a filter whose parameters are not chosen yet.
[[nodiscard]] bool searches_filter(const Candidate& c, const ChannelCorrection& accepted);

// Coefficients and searched parameters of a set of terms: the parsimony tie-break.
[[nodiscard]] std::size_t complexity(const std::vector<CorrectionTerm>& terms);

// a, then the terms of b not in a.
[[nodiscard]] std::vector<CorrectionTerm> merged(const std::vector<CorrectionTerm>& a,
                                                 const std::vector<CorrectionTerm>& b);

// The finding's evidence and feature, in the candidate's own words; `judged` says how it was
// judged ("on held-out blocks ...").
void describe(Finding& f, const Candidate& candidate, const ChannelCorrection& c,
              const ChannelData& ch, const Signals& s, const std::vector<double>& before,
              const std::vector<double>& after, const std::string& judged);

}  // namespace selfsense::diagnosis::detail
