// Force from capacitance (paper section 3.2, second method): the permittivity, hence the
// capacitance, depends on stress, so an online estimate of the incremental capacitance gives
// the load through an identified characteristic.
//
// Estimator: recursive least squares with forgetting factor lambda on the increments
//   dD[k] = c * dE[k] + e[k]          (increments cancel charge offsets and slow drift)
//   g = P dE / (lambda + dE P dE),  c += g (dD - c dE),  P = (P - g dE P) / lambda
// c is the incremental permittivity dD/dE [F/m] (times A n / h: the capacitance [F]). It needs
// excitation: a small probe signal on the drive when the working signal is quiet; samples with
// |dE| below `min_step` leave the estimate unchanged. The memory is about 1 / (1 - lambda)
// samples. Real-time safe: O(1), no allocation, no exceptions.
//
// Characteristic: T = b0 + b1 (c - c_ref) + b2 (c - c_ref)^2, fitted by least squares to a
// recording with reference stress (fit_capacitance_characteristic).
#pragma once

#include <span>
#include <string>

namespace selfsense::models {

class CapacitanceEstimator final {
 public:
  struct Params {
    double forgetting{0.999};        // lambda in (0, 1]
    double initial_estimate{0.0};    // c at start [F/m]
    double initial_variance{1e-10};  // P at start
    double min_step{0.0};            // |dE| below this does not update [V/m]

    [[nodiscard]] bool is_valid(std::string* why) const;
  };

  // Throws operators::ParameterError naming the parameter.
  explicit CapacitanceEstimator(const Params& params);

  // New sample of field and displacement; returns the current estimate.
  double step(double e, double d) noexcept;
  [[nodiscard]] double estimate() const noexcept { return c_; }
  [[nodiscard]] double variance() const noexcept { return p_; }

 private:
  Params params_{};
  double c_{0.0};
  double p_{0.0};
  double e_prev_{0.0};
  double d_prev_{0.0};
  bool primed_{false};
};

struct CapacitanceCharacteristic {
  double reference{0.0};  // c_ref [F/m]
  double b0{0.0};         // [Pa]
  double b1{0.0};         // [Pa / (F/m)]
  double b2{0.0};

  [[nodiscard]] double stress(double c) const noexcept {
    const double x = c - reference;
    return b0 + (b1 + b2 * x) * x;
  }
};

// Least squares over samples where both are given; throws std::invalid_argument if the sizes
// differ, there are fewer than 3 samples or the capacitance does not vary.
[[nodiscard]] CapacitanceCharacteristic fit_capacitance_characteristic(
    std::span<const double> capacitance, std::span<const double> stress, bool quadratic = true);

}  // namespace selfsense::models
