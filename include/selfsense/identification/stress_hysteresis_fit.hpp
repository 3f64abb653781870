// Identification of the stress-dependent hysteresis model (models/stress_hysteresis.hpp).
// Not real-time code.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "selfsense/models/stress_hysteresis.hpp"

namespace selfsense::identification {

// Fits both sides by least squares (W0 partial sums bounded below so the field dependence stays
// increasing, W1 shaped as below unless asked free, the rest free) on `plays` plays spread up to
// half the field range, from the remanent state that explains the start of the sensed channel (D,
// or S without it) best: the candidates of remanent_state.hpp ranked by the affine-in-T operator
// fit, the last turning point then refined with this model's own residual. The reconstruction range
// is the recorded stress range widened by a tenth of its span on each side. With creep sizes, the
// columns hold creep lags too (eigenvalues log-spaced like the sides' creep, operator_fit.hpp:
// fastest min(100, 0.1 / Ts), slowest min(3 / duration, fastest / 2), on the play of threshold 0
// and creep_plays plays spread over the rest), each with its own weight in W0 and in W1; their
// weights are free. row_step: the least squares take every row_step-th sample
// (OperatorStructure::row_step). loop_change: how W1, the stress's change of the loop, is
// parametrised on the plays (below). Throws std::invalid_argument on mismatched or empty
// signals.
//
// The loop change. Free, W1 has a weight per play, so the loop's change with stress can take
// any shape. Identified on a recording whose load moves a few MPa about one preload, that shape
// follows the noise and the model's own mismatch as much as the stress, and it carries badly to
// another preload. Shaped (the default), the change is the loop scaled by a quadratic in the
// threshold, W1_i = W0_i (c0 + c1 x_i + c2 x_i^2), x_i the play's threshold mapped onto
// [-1, 1]: c0 the loop's size, c1 and c2 how its narrow and wide relays change apart. The
// field's own play (the permittivity's change) and the creep lags keep a free W1 each. So the
// stress's terms are 4 + lags parameters per side instead of plays + lags. On the independent
// stack of tests/diagnosis (seeds 3400001, 3400006, 3400007, 3400014), identified at one
// preload and validated at another: D nrmse 0.076 / 0.024 / 0.199 / 0.084 % free, 0.026 /
// 0.023 / 0.036 / 0.035 % shaped, against 0.017-0.021 % fitted (measured-only).
enum class LoopChange : std::uint8_t {
  kShaped,  // the loop scaled by a quadratic in the threshold
  kFree,    // a weight per play
};

struct StressCreepSizes {
  std::size_t eigenvalues{0};      // creep lags per creep play; 0: no creep
  std::size_t creep_plays{0};      // creep plays besides threshold 0
  double fastest_eigenvalue{0.0};  // [1/s]; 0: min(100, 0.1 / Ts)
  double slowest_eigenvalue{0.0};  // [1/s]; 0: min(3 / duration, fastest / 2)
};
[[nodiscard]] models::StressHysteresisModel fit_stress_hysteresis(
    std::span<const double> e, std::span<const double> t, std::span<const double> d,
    std::span<const double> s, double sample_time, std::size_t plays,
    const StressCreepSizes& creep = {}, std::size_t row_step = 1,
    LoopChange loop_change = LoopChange::kShaped);

}  // namespace selfsense::identification
