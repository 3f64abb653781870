// Online estimate of the sensor side's drift from E and D alone (issue 24, docs/adaptation.md):
// the relative change of the permittivity (epsilon) and of the hysteresis loop (lambda) against
// the model identified at the reference temperature, by recursive least squares with
// forgetting on field increments, and the equivalent temperature that the permittivity change
// means.
//
// Measurement model (field drive; the model's sensor response split into its linear capacitive
// part L and the loop H, adapted_reconstruction.hpp's SideSplit; the stress coupling d):
//   D = y0 + (1 + epsilon) L + (1 + lambda) H + d' T                                [C/m^2]
// Between an anchor sample a and the present sample k (delta x = x[k] - x[a]):
//   z = delta D - delta L - delta H = epsilon delta L + lambda delta H + d' delta T
// The stress is unknown, but it moves slowly against the field over the short interval between
// anchor and update, so d' delta T is noise; a constant stress, a charge offset and a slow
// charge drift cancel in the increments.
//
// Parameters: with learn_loop false (default) one, epsilon, and the loop tied to it through the
// coefficients per K, lambda = (loop_per_k / permittivity_per_k) epsilon, so
//   phi = delta L + (loop_per_k / permittivity_per_k) delta H;
// with learn_loop two, phi = [delta L, delta H], theta = [epsilon, lambda].
//
// Gates (excitation): an update happens only when |delta E| >= min_field_step_v_per_m within
// max_interval_s of the anchor; then the anchor moves to k. An anchor older than
// max_interval_s moves to k without an update (a hold, or a field too slow to tell drift from
// a moving stress). A rejected sample (accepted == false: non-finite, out of range, a driver
// fault) drops the anchor, so no increment spans it. frozen: nothing is learned, the estimate
// holds.
//
// RLS with forgetting factor mu = 1 - 1 / memory_updates, applied only on updates (no
// covariance wind-up on holds):
//   K = P phi / (mu + phi' P phi),   theta += K (z - phi' theta),   P = (P - K phi' P) / mu
// then theta is clamped to +-max_relative_change and P scaled back to trace <= p0 per
// parameter. The drift is a random walk in time: every sample that is not frozen adds
// process_noise_per_s Ts to the diagonal of P (bounded the same way), held or moving, so the
// estimate itself never moves on a hold but the first updates after it weigh more; without
// it a large step's update (one increment of 50 gate steps) shrank P fifty-fold and the
// estimate stayed stiff for the next 20 s (docs/adaptation.md, "What the error is made of"). phi
// and z are divided by c0 min_field_step_v_per_m (a smallest update's capacitive increment, c0 the
// model's linear weight), so they are dimensionless and about 1.
//
// Between updates the estimate can be carried along a predicted temperature change (carry():
// the thermal model of thermal_model.hpp, a known input of the drift's process model):
//   epsilon += permittivity_per_k delta_theta,   lambda += loop_per_k delta_theta
//
// Equivalent temperature: theta_eq = reference_degc + epsilon / permittivity_per_k [degC]; the
// coupling and compliance follow it: d' = (1 + coupling_per_k (theta_eq - reference)) d.
//
// Real-time safe after construction: step(), save_state(), restore_state() are noexcept and
// allocate nothing.
#pragma once

#include <array>
#include <cstddef>
#include <span>
#include <string>

#include "selfsense/adaptation/thermal_model.hpp"

namespace selfsense::adaptation {

struct DriftEstimatorConfig {
  bool frozen{false};  // learn nothing, hold the estimate
  // false: the loop follows the permittivity through the coefficients per K,
  // lambda = (loop_per_k / permittivity_per_k) epsilon, and one parameter is learned (better
  // conditioned: L and H move together on most field paths); true: lambda is learned too.
  bool learn_loop{false};
  double min_field_step_v_per_m{20.0e3};  // excitation gate on |delta E| [V/m]
  double max_interval_s{0.05};            // longest anchor-to-update interval [s]
  double memory_updates{500.0};           // forgetting: mu = 1 - 1 / memory_updates
  double initial_variance{1.0};           // p0: P = p0 I at the start [1]
  // The drift's random walk: added to P's diagonal per second of samples, frozen excepted
  // [1/s] (0: off). Chosen on the fitting ramp (docs/adaptation.md).
  double process_noise_per_s{3.0e-5};
  double max_relative_change{0.5};  // bound on |epsilon| and |lambda| [1]
  // The temperature coefficients the drift is read with (config/plant/temperature.yaml):
  double reference_degc{25.0};        // the model's identification temperature [degC]
  double permittivity_per_k{4.0e-3};  // [1/K], must not be 0
  double loop_per_k{-4.0e-3};         // the hysteresis loop [1/K]
  double coupling_per_k{2.0e-3};      // d: the sensor coupling and the actuator's linear part
  double compliance_per_k{5.0e-4};    // the actuator's stress coupling s^E [1/K]
  // The mount (adapted_reconstruction.hpp): the load's stiffness over the stack's,
  // r = k_load / k_stack [1]; 0: a free actuator, or a load that does not follow the field.
  double load_stiffness_ratio{0.0};
  // The thermal model that carries the estimate between updates (thermal_model.hpp;
  // adapted_reconstruction.hpp runs it). Off by default: the estimate holds between updates.
  ThermalModelConfig thermal{};

  // Every value finite; steps, intervals, memory > 1, variance, bound positive; process noise
  // >= 0; permittivity_per_k non-zero; load_stiffness_ratio >= 0; the thermal model's keys
  // (thermal_model.hpp) when it is enabled. *why names the key under `prefix`
  // ("adaptation.memory_updates: must be > 1").
  [[nodiscard]] bool is_valid(const std::string& prefix, std::string* why) const;
  friend bool operator==(const DriftEstimatorConfig&, const DriftEstimatorConfig&) = default;
};

// The drift as estimated: relative changes against the model, and what they mean.
struct Drift {
  double permittivity{0.0};  // epsilon [1]: eps = (1 + epsilon) eps_ref
  double loop{0.0};          // lambda [1]: loop amplitude (1 + lambda) times the model's
  double coupling{0.0};      // d' = (1 + coupling) d: coupling_per_k times the temperature rise
  double compliance{0.0};    // s' = (1 + compliance) s
  double temperature_degc{25.0};  // the equivalent temperature
};

class DriftEstimator final {
 public:
  // c0: the model's linear capacitive weight [C/(V m)] (header comment). Throws
  // std::invalid_argument (message naming the key) on an invalid configuration, a non-positive
  // sample time or c0 <= 0.
  DriftEstimator(const DriftEstimatorConfig& config, double sample_time_s, double c0);

  // One sample: the measured field E [V/m] and displacement D [C/m^2], the model's linear
  // part L and loop part H at E [C/m^2] (header comment) and whether the sample was accepted.
  // Returns true when it updated.
  bool step(double field, double sensed, double linear_part, double loop_part,
            bool accepted) noexcept;

  [[nodiscard]] Drift drift() const noexcept;
  [[nodiscard]] std::size_t updates() const noexcept { return updates_; }
  void set_frozen(bool frozen) noexcept { config_.frozen = frozen; }
  [[nodiscard]] bool frozen() const noexcept { return config_.frozen; }
  // The next update needs a new anchor (a sample that was not seen: a driver fault).
  void drop_anchor() noexcept { anchored_ = false; }
  // Sets the drift from a measured temperature instead of learning it (a temperature sensor):
  // epsilon = permittivity_per_k dT, lambda = loop_per_k dT.
  void set_temperature(double degc) noexcept;
  // Sets epsilon and lambda (clamped to +-max_relative_change; not finite: ignored).
  void set_drift(double permittivity, double loop) noexcept;
  // Moves the estimate along a predicted temperature change (thermal_model.hpp) without
  // learning: epsilon += permittivity_per_k delta, lambda += loop_per_k delta [delta in K],
  // clamped to +-max_relative_change. Ignored when frozen or not finite.
  void carry(double delta_k) noexcept;
  [[nodiscard]] const DriftEstimatorConfig& config() const noexcept { return config_; }

  [[nodiscard]] static constexpr std::size_t state_size() noexcept { return kStateSize; }
  void save_state(std::span<double> out) const noexcept;
  void restore_state(std::span<const double> in) noexcept;

 private:
  // theta (2), P (4), anchor E, D, L, H, anchor age, anchored, updates.
  static constexpr std::size_t kStateSize{13};
  void grow_covariance() noexcept;  // the random walk's share of one sample

  DriftEstimatorConfig config_;
  double ts_{0.0};
  double growth_{0.0};  // process_noise_per_s Ts
  double scale_{1.0};   // 1 / (c0 min_field_step)
  double mu_{1.0};
  std::array<double, 2> theta_{};
  std::array<double, 4> p_{};  // row major
  double anchor_e_{0.0};
  double anchor_d_{0.0};
  double anchor_l_{0.0};
  double anchor_h_{0.0};
  double anchor_age_s_{0.0};
  bool anchored_{false};
  std::size_t updates_{0};
};

}  // namespace selfsense::adaptation
