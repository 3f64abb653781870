#include "selfsense/diagnosis/mode_undone.hpp"

#include <cmath>
#include <numbers>

#include "selfsense/models/channel_correction.hpp"

namespace selfsense::diagnosis {
namespace {

// x through a second-order Butterworth low-pass at fc (bilinear, prewarped at fc), forward and
// then backward (zero phase, |L|^2 = 1 / (1 + (f / fc)^4)); each pass starts in steady state at
// its first value.
void zero_phase_low_pass(std::vector<double>& x, double fc, double sample_time) {
  const std::size_t n = x.size();
  const double k = std::tan(std::numbers::pi * fc * sample_time);
  const double q = std::numbers::sqrt2;
  const double norm = 1.0 / (1.0 + q * k + k * k);
  const double b0 = k * k * norm;
  const double a1 = 2.0 * (k * k - 1.0) * norm;
  const double a2 = (1.0 - q * k + k * k) * norm;
  const auto pass = [&](auto index) {
    double x1 = x[index(0)];
    double x2 = x1;
    double y1 = x1;
    double y2 = x1;
    for (std::size_t i = 0; i < n; ++i) {
      double& v = x[index(i)];
      const double y = b0 * (v + 2.0 * x1 + x2) - a1 * y1 - a2 * y2;
      x2 = x1;
      x1 = v;
      y2 = y1;
      y1 = y;
      v = y;
    }
  };
  pass([](std::size_t i) { return i; });
  pass([n](std::size_t i) { return n - 1 - i; });
}

}  // namespace

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
  zero_phase_low_pass(v, frequency_hz, sample_time);
  return v;
}

}  // namespace selfsense::diagnosis
