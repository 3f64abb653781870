// The remanent state of a hysteresis operator before the first sample of a recording: the
// input history (turning points) the plays were left in. Shared by the operator fit
// (operator_fit.hpp, step 3) and the stress-dependent fit (stress_hysteresis_fit.hpp).
// Not real-time code.
#pragma once

#include <cstddef>
#include <functional>
#include <span>
#include <vector>

namespace selfsense::identification {

// Samples until x has come within 2 % of both its minimum and its maximum: after that every
// play with a threshold up to half the range has been wiped to the same state whatever the
// history was, so only these samples tell candidate histories apart.
[[nodiscard]] std::size_t sweep_length(std::span<const double> x);

// Candidate histories before the first sample x0: demagnetised at x0, or on the major loop
// (rest at one extreme, then the other) with a last turning point a before x0, a on a grid of
// 9 levels over x's range.
[[nodiscard]] std::vector<std::vector<double>> history_candidates(std::span<const double> x);

// Candidates with the last turning point a outside x's range: 1/8, 1/4, 1/2 and a whole range
// below the minimum (rising to x0) and above the maximum (falling to x0); a refinement of
// +-range/8 around the nearest covers the first range/2 without gaps. An actuator
// arrives at a recording from wherever it was driven or poled before (the simulated transducer
// from negative saturation); with plays up to half the range, a turning point a whole range
// away is as good as saturation.
[[nodiscard]] std::vector<std::vector<double>> outside_candidates(std::span<const double> x);

// Golden-section search for the last turning point a = h[end - 2] within +-step, on the same
// side of the first sample x0 = h[end - 1] (the history must still turn there); brackets it
// to 2 % of the step. residual: the score of a history (smaller is better).
[[nodiscard]] std::vector<double> refine_turning_point(
    std::vector<double> h, double step,
    const std::function<double(const std::vector<double>&)>& residual);

}  // namespace selfsense::identification
