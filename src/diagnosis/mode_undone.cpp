#include "selfsense/diagnosis/mode_undone.hpp"

#include "selfsense/models/channel_correction.hpp"

namespace selfsense::diagnosis {

std::vector<double> mode_undone(std::span<const double> w, double frequency_hz, double damping,
                                double sample_time) {
  constexpr double kRho = 0.6;
  const std::size_t n = w.size();
  if (n == 0) return {};
  const models::ModeCoefficients m = models::mode_coefficients(frequency_hz, damping, sample_time);
  const double c = (1.0 + kRho) * (1.0 + kRho) / 4.0;
  // The forward pass (A(z) / b0, then the causal first-order pass), started in steady state.
  std::vector<double> y(n);
  double w1 = w[0];
  double w2 = w[0];
  double p = c * w[0] * (1.0 + m.a1 + m.a2) / m.b0 / (1.0 + kRho);
  for (std::size_t k = 0; k < n; ++k) {
    const double u = (w[k] + m.a1 * w1 + m.a2 * w2) / m.b0;
    w2 = w1;
    w1 = w[k];
    p = c * u - kRho * p;
    y[k] = p;
  }
  // The backward pass, started in steady state, then one sample of advance.
  double next = y[n - 1] / (1.0 + kRho);
  for (std::size_t k = n; k-- > 0;) {
    next = y[k] - kRho * next;
    y[k] = next;
  }
  std::vector<double> v(n);
  for (std::size_t k = 0; k + 1 < n; ++k)
    v[k] = y[k + 1];
  v[n - 1] = y[n - 1];
  return v;
}

}  // namespace selfsense::diagnosis
