// Identification of the physics a diagnosis adds to one output channel
// (models/channel_correction.hpp). The terms before the filters are linear in their
// coefficients, and the filters (dynamics, leakage, delay) are linear time-invariant, so for
// fixed filter parameters the corrected output is
//   out = F[y] + sum_i c_i F[phi_i]
// with phi_i the term regressors (y, 1, (theta - theta_ref) y, x^2, lag outputs of y, ...) and F
// the filter chain: least squares for c. With kSecondMode the shares a and b of
// w = (1 - a - b) H1[v] + a v + b H2[v] are two more columns, R[y] - F[y] and F2[y] - F[y] (R the
// chain without a mode, F2 with the second in place of the first): linear in a and b for v = y;
// the products of a and b with the terms' coefficients are left out of the least squares (second
// order in small corrections) and kept in the corrected output, which runs the stage itself.
// The shares are fractions of the strain: a setting whose a, b or 1 - a - b leaves [0, 1] is not
// taken. The second mode is searched on the first's grid with the first fixed (as chosen, or as
// `start` gives it), then refined (with the first, where that was searched).
// Filter parameters not given are searched on a
// logarithmic grid, each point solved by least squares; the grid point is chosen by the error on
// the fitting rows only (the caller keeps other rows to judge the result).
//
// Not real-time code: allocates O(samples x terms).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "selfsense/models/channel_correction.hpp"

namespace selfsense::identification {

enum class CorrectionTerm : std::uint8_t {
  kOffset,                // gain and offset
  kTemperature,           // gain, offset, drive and (when it moves) stress per kelvin
  kTemperatureQuadratic,  // the same per kelvin squared
  kStress,                // gain per pascal (of the drive response)
  kStressQuadratic,       // T^2: a stress-dependent coupling seen on the sensed channel
  kStressDrive,           // T x and T: a permittivity (the drive's linear response) and a
                          // coupling that move with T
  kDrivePolynomial,
  kSensedQuadratic,
  kCreep,                 // log-spaced lags of y
  kDriveCreep,            // log-spaced lags of the drive x
  kDriveIntegral,         // the integral of the drive (charge through a parallel conductance)
  kHysteresis,            // plays of the drive, p_i - x (8 thresholds up to half its range)
  kAsymmetricHysteresis,  // those plays and hinges on them and on x (3 levels each)
  kDynamics,              // searched: f0, zeta
  kSecondMode,            // beside kDynamics: a second mode (searched: f2, zeta2, with the
                          // first fixed) and the shares of it and of a direct path (linear)
  kLeakage,               // searched: tau
  kDelay,                 // searched: delay
};

struct CorrectionSignals {
  std::span<const double> y{};            // the model's output of the channel
  std::span<const double> recorded{};     // the recorded channel
  std::span<const double> drive{};        // x
  std::span<const double> stress{};       // T [Pa]; empty: 0
  std::span<const double> temperature{};  // [degC]; empty: the reference
  std::span<const double> sensed{};       // the model's sensed response D - d T; empty: 0
  std::span<const double> response{};     // y - coupling T; empty: y
  double sample_time{0.0};                // [s]
  double temperature_reference_degc{25.0};
};

struct CorrectionFit {
  models::ChannelCorrection correction{};
  std::vector<double> output{};  // the corrected output over the whole recording
  double fit_sse{0.0};           // sum of squared errors on the fitting rows
};

// The least squares of a correction read at most this many of its fitting rows: every m-th
// of more, m = ceil(rows / kCorrectionFitRows); the filters and the corrected output still run
// over every sample, and fit_sse counts every fitting row. A correction has at most some 20
// coefficients, so 2e5 rows leave their variance below 1e-4 of the residual's, and the normal
// equations of a 1e6-sample record's rounds cost two fifths (docs/diagnose.md, "Speed"). Fits
// on up to 2e5 rows (every recording of up to 4e5 samples judged on half its blocks, the
// independent draws') are as before.
inline constexpr std::size_t kCorrectionFitRows = 200000;

// Fits the given terms; `start` carries filter parameters already chosen (they are kept, not
// searched again) and is otherwise ignored. fit_rows[k]: sample k may be used for fitting.
// Throws std::invalid_argument on mismatched sizes, no fitting rows, no finite fit, or a fit
// that needs 1 + gain <= 0 (the model's output inverted: not a correction of it).
[[nodiscard]] CorrectionFit fit_correction(const CorrectionSignals& signals,
                                           std::span<const CorrectionTerm> terms,
                                           const models::ChannelCorrection& start,
                                           const std::vector<bool>& fit_rows);

// Refits with folds held out (cross-validation): for each fold f, the fit on the fitting rows
// outside fold f (fold[k] = f; -1: no fold), its corrected output over the whole recording. The
// filters are those of `start` (none searched; throws std::invalid_argument otherwise). The
// regressors are computed once and each fold's share of the normal equations once, so F folds
// cost one fit and F small solves. Throws as fit_correction does.
[[nodiscard]] std::vector<std::vector<double>> held_out_outputs(
    const CorrectionSignals& signals, std::span<const CorrectionTerm> terms,
    const models::ChannelCorrection& start, const std::vector<bool>& fit_rows,
    std::span<const int> fold, std::size_t folds);

// Runs a correction over a whole recording (the runtime's CorrectionStage, so the figures are
// those the loop will see).
[[nodiscard]] std::vector<double> apply_correction(const CorrectionSignals& signals,
                                                   const models::ChannelCorrection& correction);

}  // namespace selfsense::identification
