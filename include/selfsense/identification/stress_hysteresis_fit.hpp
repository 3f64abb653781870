// Identification of the stress-dependent hysteresis model (models/stress_hysteresis.hpp).
// Not real-time code.
#pragma once

#include <cstddef>
#include <span>

#include "selfsense/models/stress_hysteresis.hpp"

namespace selfsense::identification {

// Fits both sides by least squares (W0 partial sums bounded below so the field dependence stays
// increasing, everything else free) on `plays` plays spread up to half the field range, from
// the remanent state that explains the start of the sensed channel (D, or S without it) best:
// the candidates of remanent_state.hpp ranked by the affine-in-T operator fit, the last turning
// point then refined with this model's own residual. The reconstruction range is the recorded
// stress range widened by a tenth of its span on each side. With creep sizes, the columns hold
// creep lags too (eigenvalues log-spaced like the sides' creep, operator_fit.hpp: fastest
// min(100, 0.1 / Ts), slowest min(3 / duration, fastest / 2), on the play of threshold 0 and
// creep_plays plays spread over the rest), each with its own weight in W0 and in W1; their
// weights are free. row_step: the least squares take every row_step-th sample
// (OperatorStructure::row_step). Throws std::invalid_argument on mismatched or empty signals.
struct StressCreepSizes {
  std::size_t eigenvalues{0};      // creep lags per creep play; 0: no creep
  std::size_t creep_plays{0};      // creep plays besides threshold 0
  double fastest_eigenvalue{0.0};  // [1/s]; 0: min(100, 0.1 / Ts)
  double slowest_eigenvalue{0.0};  // [1/s]; 0: min(3 / duration, fastest / 2)
};
[[nodiscard]] models::StressHysteresisModel fit_stress_hysteresis(
    std::span<const double> e, std::span<const double> t, std::span<const double> d,
    std::span<const double> s, double sample_time, std::size_t plays,
    const StressCreepSizes& creep = {}, std::size_t row_step = 1);

}  // namespace selfsense::identification
