#include "selfsense/diagnosis/mode_undone.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

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

using Polynomial = std::vector<double>;  // coefficients of z^0, z^-1, ...

Polynomial times(const Polynomial& a, const Polynomial& b) {
  Polynomial out(a.size() + b.size() - 1, 0.0);
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (std::size_t j = 0; j < b.size(); ++j)
      out[i + j] += a[i] * b[j];
  }
  return out;
}

Polynomial plus(Polynomial a, const Polynomial& b, double scale) {
  a.resize(std::max(a.size(), b.size()), 0.0);
  for (std::size_t i = 0; i < b.size(); ++i)
    a[i] += scale * b[i];
  return a;
}

// P(z^-1) with its roots (in z) moved where 1 / P is a stable recursion: those near -1 (the
// bilinear modes' zeros at Nyquist) in to modulus kNyquistRoot on their ray, as mode_undone's
// rho; any outside the unit circle to their mirror 1 / conj(r) (the same gain); any left within
// 2 % of the circle in to 0.98. P's gain at DC changes: the caller rescales.
Polynomial with_roots_inside(const Polynomial& p) {
  constexpr double kNyquistRoot = 0.6;
  constexpr double kClosest = 0.98;
  const auto degree = static_cast<Eigen::Index>(p.size()) - 1;
  if (degree < 1) return p;
  // Roots of p0 z^n + p1 z^(n-1) + ... + pn: the companion matrix's eigenvalues.
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(degree, degree);
  for (Eigen::Index i = 0; i < degree; ++i)
    companion(0, i) = -p[static_cast<std::size_t>(i + 1)] / p[0];
  for (Eigen::Index i = 1; i < degree; ++i)
    companion(i, i - 1) = 1.0;
  const Eigen::VectorXcd roots = Eigen::EigenSolver<Eigen::MatrixXd>(companion).eigenvalues();
  std::vector<std::complex<double>> q{1.0};
  for (Eigen::Index i = 0; i < degree; ++i) {
    std::complex<double> r = roots[i];
    if (std::abs(r + 1.0) < 0.2) {
      r *= kNyquistRoot / std::abs(r);
    } else if (std::abs(r) > 1.0) {
      r = 1.0 / std::conj(r);
    }
    if (std::abs(r) > kClosest) r *= kClosest / std::abs(r);
    std::vector<std::complex<double>> next(q.size() + 1, 0.0);
    for (std::size_t j = 0; j < q.size(); ++j) {
      next[j] += q[j];
      next[j + 1] -= r * q[j];
    }
    q = std::move(next);
  }
  Polynomial out(q.size());
  for (std::size_t j = 0; j < q.size(); ++j)
    out[j] = p[0] * q[j].real();
  return out;
}

double at_dc(const Polynomial& p) {
  double sum = 0.0;
  for (const double c : p)
    sum += c;
  return sum;
}

}  // namespace

std::vector<double> modes_undone(std::span<const double> w,
                                 const models::ChannelCorrection& dynamics, double sample_time) {
  const bool second = dynamics.dynamics2_frequency_hz > 0.0;
  if (dynamics.dynamics_direct == 0.0 && (!second || dynamics.dynamics2_share == 0.0)) {
    return mode_undone(w, dynamics.dynamics_frequency_hz, dynamics.dynamics_damping, sample_time);
  }
  const std::size_t n = w.size();
  if (n == 0) return {};
  const auto mode = [&](double hz, double zeta) {
    const models::ModeCoefficients m = models::mode_coefficients(hz, zeta, sample_time);
    return std::pair<Polynomial, Polynomial>{{m.b0, 2.0 * m.b0, m.b0}, {1.0, m.a1, m.a2}};
  };
  const auto [b1, a1] = mode(dynamics.dynamics_frequency_hz, dynamics.dynamics_damping);
  const auto [b2, a2] = second ? mode(dynamics.dynamics2_frequency_hz, dynamics.dynamics2_damping)
                               : std::pair<Polynomial, Polynomial>{{0.0}, {1.0}};
  const double a = dynamics.dynamics_direct;
  const double b = second ? dynamics.dynamics2_share : 0.0;
  // W = (N / D) V: N = (1 - a - b) B1 A2 + a A1 A2 + b B2 A1, D = A1 A2; V = D W / N', N' with
  // its roots drawn inside, rescaled to unity gain at DC.
  const Polynomial d = times(a1, a2);
  const Polynomial num = plus(plus(times(times(b1, a2), {1.0 - a - b}), d, a), times(b2, a1), b);
  Polynomial inside = with_roots_inside(num);
  const double scale = at_dc(d) / at_dc(inside);
  for (double& c : inside)
    c *= scale;
  std::vector<double> v(n);
  for (std::size_t k = 0; k < n; ++k) {
    double sum = 0.0;
    for (std::size_t i = 0; i < d.size(); ++i)
      sum += d[i] * (k >= i ? w[k - i] : w[0]);
    for (std::size_t i = 1; i < inside.size(); ++i)
      sum -= inside[i] * (k >= i ? v[k - i] : w[0]);
    v[k] = sum / inside[0];
  }
  const double highest = std::max(dynamics.dynamics_frequency_hz, dynamics.dynamics2_frequency_hz);
  zero_phase_low_pass(v, highest, sample_time);
  return v;
}

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
