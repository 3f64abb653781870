// A mechanical mode undone offline, so a strain channel can be re-identified without it
// (reidentified.cpp). The correction stage's mode (models::mode_coefficients) is
//   W(z) = b0 (1 + z^-1)^2 V(z) / A(z),  A(z) = 1 + a1 z^-1 + a2 z^-2,
// so V = A W / (b0 (1 + z^-1)^2). The double zero at Nyquist has no stable inverse; since
// (1 + z^-1)^2 = z^-1 (1 + z^-1)(1 + z), the factor is taken as one forward and one backward
// first-order pass with the pole at -rho instead of -1 and one sample of advance, scaled to the
// exact gain at DC:
//   u[k] = (w[k] + a1 w[k-1] + a2 w[k-2]) / b0
//   p[k] = c u[k] - rho p[k-1],  y[k] = p[k] - rho y[k+1],  v[k] = y[k+1],  c = (1 + rho)^2 / 4
// With rho = 0.6 the gain is within 3 % of the exact inverse up to 0.2 fs (1 % to 0.1 fs) and
// grows at Nyquist by (A(-1)/b0) ((1 + rho) / (1 - rho))^2 / 4 = 4 A(-1)/b0 at most: the sensor
// noise there is not blown up into the identification's target (with rho = 0.9, 90 A(-1)/b0,
// the side identified on it forecast two fast damped modes of the independent draws worse than
// a delay did: 2400003 and 2400008, traced on development draws). Not causal: the
// whole record at once, the ends held (w[-1] = w[-2] = w[0], y[n] = y[n-1]).
//
// Then v is kept to the mode's band: a second-order Butterworth low-pass at f0, forward and
// backward (zero phase, |L|^2 = 1 / (1 + (f / f0)^4)). Above the mode the recorded strain is the
// mode's tail, falling as (f0 / f)^2 under sensor noise that the inverse lifts by (f / f0)^2;
// the low-pass's (f0 / f)^4 cancels that lift, so the record undone holds the strain of the
// band and not the noise above it. A side is identified on it and forecast through the mode,
// which removes that band again. Without it, a side identified on a mode undone well below
// Nyquist had taken in the lifted noise: on the development draws (900000-900029) the modes'
// validation excess fell with it (900003 0.45 -> 0.04x, 900011 0.33 -> 0.02x, 900024 0.20 ->
// 0.02x, none worse; docs/diagnose.md, "A mode undone within its band").
#pragma once

#include <span>
#include <vector>

#include "selfsense/models/channel_correction.hpp"

namespace selfsense::diagnosis {

[[nodiscard]] std::vector<double> mode_undone(std::span<const double> w, double frequency_hz,
                                              double damping, double sample_time);

// A correction's whole dynamics block undone (models/channel_correction.hpp): with a direct path
// or a second mode, W = (N / D) V with D = A1 A2 and N = (1 - a - b) B1 A2 + a A1 A2 + b B2 A1
// (B_i = b0_i (1 + z^-1)^2). N's roots (in z) near -1 (the bilinear modes' zeros at Nyquist)
// are drawn in to modulus 0.6 (rho above), any outside the unit circle mirrored inside, any
// within 2 % of it drawn to 0.98, so V = D W / N' is a stable causal recursion, rescaled to
// unity gain at DC and started in steady state; then the zero-phase low-pass at the higher
// mode's frequency, as above. With neither, mode_undone.
[[nodiscard]] std::vector<double> modes_undone(std::span<const double> w,
                                               const models::ChannelCorrection& dynamics,
                                               double sample_time);

}  // namespace selfsense::diagnosis
