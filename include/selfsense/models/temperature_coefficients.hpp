// How a field-driven model's parameters change with the stack's temperature (issue 24 item 1,
// docs/adaptation.md "Temperature coefficients"): per side, the relative change of the linear
// capacitive part L, of the loop H and of the stress coupling, each linear and quadratic in the
// temperature change from the identification temperature. Fitted by
// adaptation/temperature_fit.hpp on a ramp recording, stored in the model file under
// `temperature:` (model_io/model_yaml.hpp), used by adaptation/adapted_reconstruction.hpp when
// the temperature is measured.
//
// With dtheta = theta - reference_degc [K] and a side's response split into L and H
// (adaptation::SideSplit), the side at theta:
//   y = y0 + q x^2 + g_L(dtheta) L + g_H(dtheta) H + g_c(dtheta) c T
//   g(dtheta) = 1 + per_k dtheta + per_k2 dtheta^2                                [1]
// Sensor side: g_L the permittivity, g_H the loop, g_c the coupling d. Actuator side: g_L the
// linear part d E, g_H the loop, g_c the compliance s^E. The offsets and quadratic terms do not
// change.
//
// The sensor side's drift as the online estimator sees it (increments, first order; optional,
// 0: none): the same fit on the field increments the estimator learns from
// (adaptation/drift_estimator.hpp), between gated samples a and k:
//   delta D - delta L - delta H - d delta T = (i_L delta L + i_H delta H) dtheta + ...
// On the main job's ramp it is not the levels' (loop -4.6e-3 against -3.1e-3 per K): the
// estimator reads its learned drift with these and the reconstruction takes the level
// polynomials at the temperature they give (docs/adaptation.md, "Levels and increments").
#pragma once

#include <string>

namespace selfsense::models {

struct TemperaturePolynomial {
  double per_k{0.0};   // [1/K]
  double per_k2{0.0};  // [1/K^2]
  [[nodiscard]] double scale(double dtheta) const noexcept {
    return 1.0 + (per_k + per_k2 * dtheta) * dtheta;
  }
  friend bool operator==(const TemperaturePolynomial&, const TemperaturePolynomial&) = default;
};

struct SideTemperature {
  TemperaturePolynomial linear{};    // L: permittivity (sensor), d E (actuator)
  TemperaturePolynomial loop{};      // H
  TemperaturePolynomial coupling{};  // d (sensor), s^E (actuator)
  friend bool operator==(const SideTemperature&, const SideTemperature&) = default;
};

// The sensor side's first-order drift on the estimator's increments (header comment).
struct IncrementTemperature {
  double linear_per_k{0.0};  // i_L: the permittivity [1/K]; 0: not fitted
  double loop_per_k{0.0};    // i_H: the loop [1/K]
  [[nodiscard]] bool fitted() const noexcept { return linear_per_k != 0.0; }
  friend bool operator==(const IncrementTemperature&, const IncrementTemperature&) = default;
};

struct TemperatureCoefficients {
  double reference_degc{25.0};  // the identification temperature [degC]
  SideTemperature sensor{};
  SideTemperature actuator{};
  IncrementTemperature increments{};  // model file: `increments: [i_L, i_H]`, optional

  // Every value finite; *why names the key under `prefix` ("temperature.sensor.loop.per_k:
  // must be finite").
  [[nodiscard]] bool is_valid(const std::string& prefix, std::string* why) const;
  friend bool operator==(const TemperatureCoefficients&, const TemperatureCoefficients&) = default;
};

}  // namespace selfsense::models
