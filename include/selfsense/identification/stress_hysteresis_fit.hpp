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
// stress range widened by a tenth of its span on each side. Throws std::invalid_argument on
// mismatched or empty signals.
[[nodiscard]] models::StressHysteresisModel fit_stress_hysteresis(
    std::span<const double> e, std::span<const double> t, std::span<const double> d,
    std::span<const double> s, double sample_time, std::size_t plays);

}  // namespace selfsense::identification
