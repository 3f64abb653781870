// Identification of the stress-dependent hysteresis model (models/stress_hysteresis.hpp).
// Not real-time code.
#pragma once

#include <cstddef>
#include <span>

#include "selfsense/models/stress_hysteresis.hpp"

namespace selfsense::identification {

// Fits both sides by least squares (W0 partial sums bounded below so the field dependence stays
// increasing, everything else free). The bracket is the recorded stress range widened by a tenth of
// its span on each side. Throws std::invalid_argument on mismatched or empty signals.
[[nodiscard]] models::StressHysteresisModel fit_stress_hysteresis(
    std::span<const double> e, std::span<const double> t, std::span<const double> d,
    std::span<const double> s, double sample_time, std::size_t plays);

}  // namespace selfsense::identification
