// The stack's temperature predicted from the power it takes (issue 24, docs/adaptation.md,
// "Following the temperature through holds"): a first-order thermal law driven by the electrical
// power E dD/dt times the stack's volume, which carries the drift estimate along while the
// excitation gate holds the recursive least squares frozen (drift_estimator.hpp).
//
// The power between samples k-1 and k (trapezoid; the loop area over a cycle, plus the
// reversible exchange that cancels over a cycle; the same integral as the health estimate's
// dissipation per cycle, health_estimator.hpp):
//   P_k = V (E[k] + E[k-1]) / 2 (D[k] - D[k-1]) / Ts                                  [W]
// with V = stack_volume_m3 [m^3], E [V/m], D [C/m^2] and Ts the sample time [s].
//
// The thermal law, dtheta/dt = (R_th P - (theta - theta_amb)) / tau_th, discretised exactly
// for a power held over the sample (a = exp(-Ts / tau_th)):
//   theta[k+1] = theta_amb + a (theta[k] - theta_amb) + (1 - a) R_th P_k              [degC]
// with R_th = resistance_k_per_w [K/W], tau_th = time_constant_s [s] and theta_amb =
// ambient_degc [degC], the plant's datasheet values (a user knows them, or measures them once
// from a warming run: docs/adaptation.md).
//
// theta[k] is not a state of its own: it is the present estimate (the adapted equivalent
// temperature, learned while the excitation makes it observable), so the law only says how it
// moves from one sample to the next. Between updates of the estimator that is all it does
// (the hold's cooling); during the excitation the estimator corrects it at every update, so a
// wrong R_th or tau_th is corrected there and matters only for the holds.
//
// A rejected sample (accepted false, or inputs not finite) contributes no power and the next
// increment starts from the next accepted sample. The power is bounded by +-max_power_w.
//
// Real-time safe after construction: step(), save_state(), restore_state() are noexcept and
// allocate nothing.
#pragma once

#include <cstddef>
#include <span>
#include <string>

namespace selfsense::adaptation {

struct ThermalModelConfig {
  bool enabled{false};               // false: the estimate holds between updates
  double resistance_k_per_w{50.0};   // R_th, stack to ambient [K/W]
  double time_constant_s{600.0};     // tau_th [s]
  double ambient_degc{25.0};         // theta_amb [degC]
  double stack_volume_m3{2.505e-7};  // V: layers x electrode area x layer thickness [m^3]
  double max_power_w{100.0};         // bound on |P| [W]

  // Every value finite; resistance >= 0; time constant, volume and power bound positive. *why
  // names the key under `prefix` in base/check.hpp's format
  // ("adaptation.thermal_time_constant_s: 0 must be > 0").
  [[nodiscard]] bool is_valid(const std::string& prefix, std::string* why) const;
  friend bool operator==(const ThermalModelConfig&, const ThermalModelConfig&) = default;
};

class ThermalModel final {
 public:
  // Throws std::invalid_argument (message naming the key) on an invalid configuration or a
  // non-positive sample time.
  ThermalModel(const ThermalModelConfig& config, double sample_time_s);

  // One sample: the measured field E [V/m] and displacement D [C/m^2]; updates the power P_k.
  void step(double field, double sensed, bool accepted) noexcept;
  // theta[k+1] from theta[k] [degC] with the last power (header comment).
  [[nodiscard]] double predict(double temperature_degc) const noexcept;
  [[nodiscard]] double power_w() const noexcept { return power_w_; }
  [[nodiscard]] const ThermalModelConfig& config() const noexcept { return config_; }

  [[nodiscard]] static constexpr std::size_t state_size() noexcept { return kStateSize; }
  void save_state(std::span<double> out) const noexcept;
  void restore_state(std::span<const double> in) noexcept;

 private:
  // The previous accepted E and D, whether there is one, the last power.
  static constexpr std::size_t kStateSize{4};

  ThermalModelConfig config_;
  double ts_{0.0};
  double decay_{1.0};  // a = exp(-Ts / tau_th)
  double last_e_{0.0};
  double last_d_{0.0};
  bool has_last_{false};
  double power_w_{0.0};
};

}  // namespace selfsense::adaptation
