// Diagnosis of a transducer model against a recording (selfsense diagnose, docs/diagnose.md):
// locate where they differ, name the physics the model leaves out, model it, show the fit
// improve. Pure math: signals in, a result and the improved model out.
//
// For each output channel the model has and the recording references (D, S):
//   1. residual e = recorded - model; correlation tests and large segments (residual_tests.hpp)
//   2. every candidate effect (docs/diagnose.md) that the channel can show (src/diagnosis/
//      candidates.cpp) is fitted as a correction (models/channel_correction.hpp,
//      identification/correction_fit.hpp) on the fitting blocks only (alternate twentieths of
//      the record), and judged on the other blocks: explains = 1 - SSE_after / SSE_before there
//   3. the best significant candidate is accepted (statistics.hpp): its held-out gain passes
//      the signed-rank test over the held-out blocks at 99 %, it explains at least
//      `min_explains` of the held-out residual and makes no block much worse; creep, which
//      lives in the holds after steps, may instead pass on held-out holds (each hold refitted
//      without it: the movement within the holds explained, in two or more), and a hysteresis
//      operator, which can draw any level, must also leave the held-out holds no worse; of
//      candidates explaining about as much, the simplest wins; candidates that pass too and
//      explain nearly as much are reported as alternatives, with their own evidence; then the
//      search repeats on what is left (several effects in turn), refitting the accepted terms
//      jointly with each new candidate
//   4. the accepted corrections go into the model, which the runtime runs per sample.
//   5. the verdict: mismatch with a finding; without one, unexplained when a channel's residual
//      stands well above its noise floor (statistics.hpp), else consistent.
// A model that already carries corrections is diagnosed from its sides alone (its corrections
// are found again if still needed).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "selfsense/diagnosis/residual_tests.hpp"
#include "selfsense/models/transducer_model.hpp"

namespace selfsense::diagnosis {

// A recording in field quantities; empty spans: channel absent.
struct Signals {
  std::span<const double> drive{};        // E (field drive) or D (charge drive)
  std::span<const double> sensed{};       // D (or E)
  std::span<const double> strain{};       // S
  std::span<const double> stress{};       // T [Pa]
  std::span<const double> temperature{};  // [degC]
  double sample_time{0.0};
};

struct Options {
  double min_explains{0.3};  // share of held-out residual variance an effect must remove
  double min_share{0.02};    // ... and at least this share of the channel's first residual
  // ... and in no held-out block may it add more than this share to the residual variance, or
  // than the share it removes over all held-out blocks together where that is larger.
  double max_block_loss{0.2};
  double alternative_share{0.8};  // alternatives: explain at least this share of the best's
  // A simpler candidate wins when the residual it leaves is at most this factor of the best's.
  double parsimony_ratio{1.25};
  // A hysteresis operator (generic: it bends to many residuals) is chosen over significant
  // specific physics only when the residual it leaves is at most this factor of theirs.
  double generic_ratio{0.5};
  // A candidate whose fit rescales the model's output by more than this (relative) is not one.
  double max_gain{1.0};
  std::size_t max_effects{4};  // per channel
  std::size_t blocks{20};      // alternate blocks for fitting and judging
  // A residual is "well above the noise floor" when its RMS exceeds this factor of the noise
  // floor (statistics.hpp): at 5, 96 % of its variance is model error, not sensor noise.
  double unexplained_ratio{5.0};
};

// Another effect that explains nearly as much of the same residual, with its own evidence: the
// data cannot tell the two apart, so both are reported.
struct Alternative {
  std::string effect{};
  double explains{0.0};
  std::string evidence{};
};

struct Finding {
  std::string effect{};   // the effect's name (docs/diagnose.md)
  std::string channel{};  // "D" / "S" (or "E" for charge drive)
  std::vector<Segment> where{};
  double explains{0.0};
  std::string evidence{};
  std::vector<Alternative> alternatives{};  // other effects explaining nearly as much
  std::string feature_name{};
  std::vector<double> feature{};  // the explaining feature per sample
};

struct ChannelResult {
  std::string channel{};
  double noise_floor{0.0};   // of the residual before (statistics.hpp), channel units
  double residual_rms{0.0};  // the residual left (after the findings), channel units
  std::vector<double> recorded{};
  std::vector<double> before{};
  std::vector<double> after{};
  std::vector<Segment> located{};
  CorrelationTest test_before{};
  CorrelationTest test_after{};
};

// A residual well above the noise floor that no candidate reduces on held-out data: where it is
// and how much of it that is.
struct Unexplained {
  std::string channel{};
  std::vector<Segment> where{};  // the stretches that hold most of it (or the whole record)
  double share{0.0};             // of the residual's energy in `where`
  double residual_rms{0.0};      // channel units
  double noise_floor{0.0};       // channel units
};

// mismatch: at least one finding; unexplained: none, but a residual well above the noise floor
// (Unexplained); consistent: none, and every residual near its noise floor.
enum class Verdict : std::uint8_t { kConsistent, kMismatch, kUnexplained };
[[nodiscard]] const char* to_string(Verdict v) noexcept;

struct Result {
  bool mismatch{false};
  Verdict verdict{Verdict::kConsistent};
  std::vector<Finding> findings{};
  std::vector<Unexplained> unexplained{};  // channels without a finding whose residual stands out
  std::vector<ChannelResult> channels{};
  models::TransducerModel improved{};
};

// Throws std::invalid_argument on unusable signals (no drive, sizes differ, no referenced
// output the model has) and on Options.blocks < 14 (fewer than 7 blocks to judge on).
[[nodiscard]] Result diagnose(const models::TransducerModel& model, const Signals& signals,
                              const Options& options = {});

// The model's outputs (sensed, strain) over a recording, per sample through the runtime model.
struct Outputs {
  std::vector<double> sensed{};
  std::vector<double> strain{};
};
[[nodiscard]] Outputs simulate(const models::TransducerModel& model, const Signals& signals);

}  // namespace selfsense::diagnosis
