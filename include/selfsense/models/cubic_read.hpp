// A sampled signal read between its samples by the cubic Lagrange interpolator through four of
// them: the value at i + t (t in [0, 1]) is
//   v = w0 x[i-1] + w1 x[i] + w2 x[i+1] + w3 x[i+2],
//   w0 = -t (t-1)(t-2)/6,  w1 = (t+1)(t-1)(t-2)/2,  w2 = -(t+1) t (t-2)/2,  w3 = (t+1) t (t-1)/6.
// Exact for cubics, and at t = 0 and t = 1 the samples themselves. Why not linear: a component of
// w rad per sample read linearly loses about t (1 - t) w^2 / 2 of itself (a low-pass); the cubic
// read's error is about |(t+1) t (t-1)(t-2)| w^4 / 24 (2e-4 of the component at 0.3 rad per
// sample, t = 1/2).
#pragma once

#include <array>

namespace selfsense::models {

[[nodiscard]] constexpr std::array<double, 4> cubic_read_weights(double t) noexcept {
  return {-t * (t - 1.0) * (t - 2.0) / 6.0, (t + 1.0) * (t - 1.0) * (t - 2.0) / 2.0,
          -(t + 1.0) * t * (t - 2.0) / 2.0, (t + 1.0) * t * (t - 1.0) / 6.0};
}

}  // namespace selfsense::models
