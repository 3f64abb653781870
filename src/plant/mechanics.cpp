#include "selfsense/plant/mechanics.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <numbers>

namespace selfsense::plant {

namespace {

// exp(M) by scaling and squaring with a 16-term Taylor series; M is small and well scaled.
Eigen::Matrix4d expm(const Eigen::Matrix4d& m) {
  const double norm = m.cwiseAbs().rowwise().sum().maxCoeff();
  int squarings = 0;
  if (norm > 0.5) squarings = static_cast<int>(std::ceil(std::log2(norm / 0.5)));
  const Eigen::Matrix4d a = m / std::ldexp(1.0, squarings);
  Eigen::Matrix4d term = Eigen::Matrix4d::Identity();
  Eigen::Matrix4d sum = Eigen::Matrix4d::Identity();
  for (int i = 1; i <= 16; ++i) {
    term = term * a / static_cast<double>(i);
    sum += term;
  }
  for (int i = 0; i < squarings; ++i)
    sum = sum * sum;
  return sum;
}

}  // namespace

Mechanics::Mechanics(double resonance_hz, double damping_ratio, double sample_time_s) {
  const double w = 2.0 * std::numbers::pi * resonance_hz;
  Eigen::Matrix4d m = Eigen::Matrix4d::Zero();
  m(0, 1) = 1.0;
  m(1, 0) = -w * w;
  m(1, 1) = -2.0 * damping_ratio * w;
  m(1, 2) = w * w;
  m(2, 3) = 1.0;  // x_eq ramps with slope state 3
  const Eigen::Matrix4d e = expm(m * sample_time_s);
  phi_[0][0] = e(0, 0);
  phi_[0][1] = e(0, 1);
  phi_[1][0] = e(1, 0);
  phi_[1][1] = e(1, 1);
  g0_[0] = e(0, 2);
  g0_[1] = e(1, 2);
  g1_[0] = e(0, 3) / sample_time_s;
  g1_[1] = e(1, 3) / sample_time_s;
}

double Mechanics::peek(double x_eq) const noexcept {
  const double slope = x_eq - x_eq_prev_;
  return phi_[0][0] * x_ + phi_[0][1] * v_ + g0_[0] * x_eq_prev_ + g1_[0] * slope;
}

double Mechanics::update(double x_eq) noexcept {
  const double slope = x_eq - x_eq_prev_;
  const double x = peek(x_eq);
  const double v = phi_[1][0] * x_ + phi_[1][1] * v_ + g0_[1] * x_eq_prev_ + g1_[1] * slope;
  x_eq_prev_ = x_eq;
  x_ = x;
  v_ = v;
  return x_;
}

}  // namespace selfsense::plant
