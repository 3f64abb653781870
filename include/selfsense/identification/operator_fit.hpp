// Identification of a hysteresis-creep operator with linear side inputs from a recording.
//
//   y = S[ H[x] + K[x] ] + sum_k g_k u_k + offset
//
// H: PI operator (linear term + `plays` plays), with bias_levels hinges on each play a
// Preisach operator (operators/play_hinges.hpp), K: creep elements (eigenvalues x creep
// thresholds), S: dead-zone superposition, u_k: inputs that enter linearly (stress T for the
// paper's eq. 26-27). Every transducer structure is a special case: no plays, no creep and no
// dead zones is the linear model (5-6); dead zones alone a stored characteristic (9-13); x = D
// and y = E the charge-driven model of Jones and Garcia (18).
//
// The fit is convex and deterministic (no random restarts):
//  1. weights enter linearly; with the partial sums W_i = w_0 + ... + w_i as unknowns the
//     invertibility condition W_i > 0 is a simple bound, creep weights are >= 0 (hinge weights
//     are free): a bounded
//     least-squares problem on the normal equations (solve_bounded_least_squares);
//  2. with dead zones, the inverse superposition S' = S^-1 is fitted in the same way on the
//     equation error S'[y - g u - offset] = H[x] + K[x] (Kuhnen's modified-PI identification),
//     with g and offset from step 1, and inverted in closed form; then output-error passes
//     alternate between S, g, offset (linear in them for a fixed H + K) and a Gauss-Newton
//     step for H + K, g, offset (exact on each linear piece of S), each a bounded least-squares
//     problem again; the fit with the smallest output error is kept;
//  3. unless given (OperatorStructure::start), the remanent state before the first sample is
//     chosen among candidate input histories (remanent_state.hpp: a last turning point on a
//     grid inside and beyond the recorded range, and the demagnetised start): cheap proxies of
//     the basis rank those inside the range, then the whole basis decides between their picks
//     and the rest over the whole recording and refines the winner's turning point; with dead
//     zones a second time through the fitted S^-1 (docs/identification.md).
// Thresholds follow from the input's range, creep eigenvalues from the sample time and the
// duration. Not real-time code.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "selfsense/models/side_model.hpp"
#include "selfsense/operators/hysteresis_creep.hpp"

namespace selfsense::identification {

struct OperatorStructure {
  std::size_t plays{0};        // play operators besides the linear term
  std::size_t eigenvalues{0};  // creep lags; 0: no creep
  std::size_t creep_plays{0};  // creep elements on plays besides r = 0
  std::size_t dead_zones{0};   // per side of the superposition; 0: S = identity
  // Hinges per play (play_hinges.hpp: the Preisach class) at levels spread evenly over the
  // play's output range; 0: a PI operator.
  std::size_t bias_levels{0};
  double fastest_eigenvalue{0.0};  // [1/s]; 0: min(100, 0.1 / Ts)
  double slowest_eigenvalue{0.0};  // [1/s]; 0: 3 / duration
  bool estimate_history{true};     // false: start demagnetised at the first input
  // The remanent state at the first sample when it is known (a history of input turning
  // points ending at the first input, SideModel::history): no search. A fit of the same input
  // with another output (an effect undone) starts where the drive left the stack either way,
  // and on a long record the search costs most of the fit (docs/identification.md).
  std::vector<double> start{};
  bool fit_offset{true};
  std::size_t refinement_passes{2};  // output-error passes after the equation error (dead zones)
  // The normal equations take every row_step-th sample (the operators still run through every
  // sample), each weighted by row_step so that sums and residuals keep the units of every
  // sample: on a long, oversampled record the least squares cost a fraction while the
  // parameters' variance grows by the same factor, from far below the residual's (p / n).
  // 1: every sample.
  std::size_t row_step{1};
};

// The row step of a ranking among candidates (the remanent state's histories, the stress
// structure's play counts) on a fit of row step `fitted`. A record within the caller's row
// budget (1) ranks them on every sample, as it is fitted. A longer one ranks them on every 4th
// fitted row: a ranking reads the systematic misfit of some 30-100 columns, which a quarter of
// up to 2e5 rows still resolves, and on a 1e6-sample record the rankings cost half of
// `selfsense diagnose` (docs/diagnose.md, "Speed"). The winner is then fitted on every fitted
// row.
[[nodiscard]] constexpr std::size_t ranking_row_step(std::size_t fitted) noexcept {
  constexpr std::size_t kThinning = 4;
  return fitted > 1 ? fitted * kThinning : 1;
}

struct OperatorSignals {
  std::span<const double> input{};                       // x
  std::vector<std::span<const double>> linear_inputs{};  // u_k
  std::span<const double> output{};                      // y
  double sample_time{0.0};                               // [s]
};

// The fitted side (models/side_model.hpp): the runtime models run it without this library.
using OperatorModel = models::SideModel;

// Throws std::invalid_argument on empty or mismatched signals, a non-positive sample time or
// a constant input.
[[nodiscard]] OperatorModel fit_operator(const OperatorSignals& signals,
                                         const OperatorStructure& structure);

// y = model response to x and the linear inputs, starting from the model's history.
void simulate_operator(const OperatorModel& model, std::span<const double> x,
                       const std::vector<std::span<const double>>& linear_inputs,
                       std::span<double> y);

}  // namespace selfsense::identification
