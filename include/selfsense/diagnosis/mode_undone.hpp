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
#pragma once

#include <span>
#include <vector>

namespace selfsense::diagnosis {

[[nodiscard]] std::vector<double> mode_undone(std::span<const double> w, double frequency_hz,
                                              double damping, double sample_time);

}  // namespace selfsense::diagnosis
