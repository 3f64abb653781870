// Plants and measurements for the control-law tests: simulated in sample time, deterministic.
#pragma once

#include <cmath>
#include <cstddef>
#include <numbers>
#include <span>

namespace selfsense::control::test {

// y' = (K u - y) / T, exact for u held over each sample: y[k+1] = a y[k] + (1 - a) K u[k].
class FirstOrderPlant {
 public:
  FirstOrderPlant(double gain, double time_constant, double sample_time)
      : gain_(gain), a_(std::exp(-sample_time / time_constant)) {}
  [[nodiscard]] double output() const { return y_; }
  void advance(double u) { y_ = a_ * y_ + (1.0 - a_) * gain_ * u; }

 private:
  double gain_{1.0};
  double a_{0.0};
  double y_{0.0};
};

// x'' + 2 zeta w x' + w^2 x = w^2 u (static gain 1), u held over each sample, integrated by RK4
// with `substeps` steps per sample.
class ResonantPlant {
 public:
  ResonantPlant(double frequency, double damping, double sample_time, int substeps = 8)
      : w_(2.0 * std::numbers::pi * frequency),
        zeta_(damping),
        h_(sample_time / substeps),
        substeps_(substeps) {}
  void set_position(double x) { x_ = x; }
  [[nodiscard]] double position() const { return x_; }
  void advance(double u) {
    for (int i = 0; i < substeps_; ++i) {
      const auto acc = [&](double x, double v) { return w_ * w_ * (u - x) - 2.0 * zeta_ * w_ * v; };
      const double k1x = v_;
      const double k1v = acc(x_, v_);
      const double k2x = v_ + 0.5 * h_ * k1v;
      const double k2v = acc(x_ + 0.5 * h_ * k1x, k2x);
      const double k3x = v_ + 0.5 * h_ * k2v;
      const double k3v = acc(x_ + 0.5 * h_ * k2x, k3x);
      const double k4x = v_ + h_ * k3v;
      const double k4v = acc(x_ + h_ * k3x, k4x);
      x_ += h_ / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
      v_ += h_ / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
    }
  }

 private:
  double w_{0.0};
  double zeta_{0.0};
  double h_{0.0};
  int substeps_{1};
  double x_{0.0};
  double v_{0.0};
};

// Amplitude of the component at frequency f [Hz] in y, sampled at Ts from sample index
// `first`: least squares on sin and cos over y (use a whole number of periods).
inline double amplitude_at(std::span<const double> y, double frequency, double sample_time,
                           std::size_t first) {
  double s = 0.0;
  double c = 0.0;
  for (std::size_t k = 0; k < y.size(); ++k) {
    const double phase =
        2.0 * std::numbers::pi * frequency * sample_time * static_cast<double>(first + k);
    s += y[k] * std::sin(phase);
    c += y[k] * std::cos(phase);
  }
  return 2.0 * std::hypot(s, c) / static_cast<double>(y.size());
}

// Time [s] after which |y| stays at or below `level`.
inline double settle_time(std::span<const double> y, double level, double sample_time) {
  std::size_t last = 0;
  for (std::size_t k = 0; k < y.size(); ++k) {
    if (std::abs(y[k]) > level) last = k + 1;
  }
  return static_cast<double>(last) * sample_time;
}

}  // namespace selfsense::control::test
