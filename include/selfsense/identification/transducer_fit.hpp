// Identification of a transducer model (models/transducer_model.hpp) from recorded signals:
// one entry point for every structure. The sides are fitted by fit_operator (operator_fit.hpp),
// the stress-dependent model by fit_stress_hysteresis. Not real-time code.
#pragma once

#include <array>
#include <cstddef>
#include <functional>
#include <span>
#include <vector>

#include "selfsense/identification/stress_hysteresis_fit.hpp"
#include "selfsense/models/transducer_model.hpp"

namespace selfsense::identification {

using models::Structure;
using models::TransducerModel;

// Sizes of the operators an identification uses; defaults per structure (defaults_for).
struct IdentificationOptions {
  std::size_t plays{0};
  std::size_t eigenvalues{0};
  std::size_t creep_plays{0};
  std::size_t dead_zones{0};
  bool estimate_history{true};
  double fastest_eigenvalue{0.0};  // [1/s]; 0: from the sample time (OperatorStructure)
  double slowest_eigenvalue{0.0};  // [1/s]; 0: from the duration
  std::size_t bias_levels{0};      // hinges per play (OperatorStructure::bias_levels)
  // preisach-creep chooses sizes per side on the fitting data alone, by the output error on
  // its last quarter of a fit on the first three quarters: dead zones between 0 and
  // dead_zones, then bias_levels among kBiasLevelCandidates (levels at k / (n + 1) of the
  // input range: each count's levels contain the smaller ones', so a larger count never fits
  // worse).
  bool choose_bias_levels{false};
  bool choose_dead_zones{false};
  // stress-hysteresis takes eigenvalues and creep_plays as creep lags among its columns
  // (stress_hysteresis_fit.hpp; default none) and chooses its play count among
  // kStressPlayCandidates on the fitting data alone: the reconstruction error (T_hat, and S_hat
  // with a strain channel) on the last quarter of a fit on the first three quarters.
  bool choose_plays{false};
  // stress-hysteresis: how the stress changes the loop (stress_hysteresis_fit.hpp).
  LoopChange loop_change{LoopChange::kShaped};
  // The fitted side's remanent state at the first sample, when known (OperatorStructure::start;
  // not for stress-hysteresis): the diagnosis's trials of one recording take their null's.
  std::vector<double> start{};
  // At most this many samples are rows of each least-squares fit: every m-th sample with
  // m = ceil(n / max_rows), weighted by m (OperatorStructure::row_step), the operators still
  // run through every sample. 0: every sample.
  std::size_t max_rows{0};
};
inline constexpr std::array<std::size_t, 4> kBiasLevelCandidates{0, 1, 3, 7};
inline constexpr std::array<std::size_t, 3> kStressPlayCandidates{16, 24, 48};
[[nodiscard]] IdentificationOptions defaults_for(Structure s) noexcept;

// Recorded signals in field quantities. drive is E (field drive) or D (charge drive), sensed
// the other one. Empty sensed: no sensor side; empty strain: no actuator side; empty stress:
// the free actuator (T = 0, couplings not identifiable, so no reconstruction of T).
struct TransducerSignals {
  std::span<const double> drive{};
  std::span<const double> sensed{};
  std::span<const double> stress{};
  std::span<const double> strain{};
  double sample_time{0.0};
};

// Runs independent pieces of work and returns when each has run, rethrowing an exception one of
// them threw. identify() hands it the fits of the two sides, which share nothing but the
// signals they read. This library runs no threads (docs/architecture.md): a program that may
// passes a runner that runs the pieces in parallel (`selfsense identify`); without one they run
// one after the other. Either way the same fits, so the same model.
using WorkRunner = std::function<void(std::span<const std::function<void()>>)>;

// Fits the sides the signals allow. Throws std::invalid_argument on unusable signals (no drive,
// neither sensed nor strain, mismatched lengths).
[[nodiscard]] TransducerModel identify(const TransducerSignals& signals, Structure structure,
                                       const IdentificationOptions& options,
                                       const WorkRunner& run = {});

}  // namespace selfsense::identification
