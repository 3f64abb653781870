// The statistics a diagnosis decides by (docs/diagnose.md, "Decisions"). Pure math.
//
// Noise floor of a channel: the standard deviation of the white part of a residual e, from its
// second difference
//   d2[k] = e[k+1] - 2 e[k] + e[k-1],   var(d2) = 6 sigma^2 for white e,
// taken robustly, sigma = 1.4826 MAD(d2) / sqrt(6): what a model misses moves slowly against the
// sample rate (its second difference is small) except at a few steps, which the median ignores,
// while sensor noise is white: it reads the residual near the Nyquist frequency, far above the
// excitation's band (noise filtered before sampling reads lower; a recording quantised more
// coarsely than its noise reads 0 and makes any model error stand out).
//
// Held-out gain: a candidate refitted without some blocks predicts them; per held-out block b
// the gain is g_b = SSE_before,b - SSE_after,b. It is significant when Wilcoxon's signed-rank
// test rejects "the gains are symmetric about zero" one-sided at `kConfidence`: rank |g_b|,
// W- = the sum of the ranks of the gains <= 0 (a block that does not gain counts against it;
// ties, improbable for real-valued gains, are ranked in order), p = P(W- <= observed) under the
// null
// (every sign equally likely: 2^B sign patterns, counted exactly). Only signs and ranks count,
// so an effect that lives in a few blocks (a delay at the fast moves, leakage late in a run)
// is as significant as one spread evenly, as long as the other blocks do not get worse; blocks
// long against the residual's correlation time are nearly independent. A fit that only fits its
// own rows gains nothing on the others, which is the penalty for its complexity.
#pragma once

#include <cstddef>
#include <span>

namespace selfsense::diagnosis {

// One-sided confidence of every significance test of the diagnosis.
inline constexpr double kConfidence = 0.99;

// The noise floor (standard deviation) of a residual; 0 for fewer than 8 samples.
[[nodiscard]] double noise_floor(std::span<const double> residual);

struct GainTest {
  std::size_t blocks{0};    // blocks with a residual
  double w_minus{0.0};      // the rank sum of the blocks that got worse
  double p_value{1.0};      // P(W- <= w_minus) with every sign equally likely
  bool significant{false};  // p_value <= 1 - kConfidence
};

// The signed-rank test over blocks with SSE before and after (equal sizes); blocks without a
// residual before are left out; a non-finite gain makes the test fail (p = 1).
[[nodiscard]] GainTest paired_gain_test(std::span<const double> before,
                                        std::span<const double> after);

}  // namespace selfsense::diagnosis
