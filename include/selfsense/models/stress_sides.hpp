// A stress-hysteresis model (stress_hysteresis.hpp) completed by plain sides
// (transducer_model.hpp) where it has none. A diagnosis that finds the stress dependence on one
// channel replaces that channel's side only: the other keeps the side it was identified with,
// whose dead zones and creep can fit it better than the stress structure's plays. With q the
// play columns of the field and Gs, Ga the plain sides' hysteresis-creep operators:
//   stress-dependent sensor, plain actuator
//     forward          D = W0.q + T (W1.q) + d1 T + d2 T^2 + D0,   S = Ga[E] + sE T + S0
//     reconstruction   T_hat from the sensor's quadratic (stress_hysteresis.hpp),
//                      S_hat = Ga[E] + sE T_hat + S0
//   plain sensor, stress-dependent actuator
//     forward          D = Gs[E] + d T + D0,   S = A0.q + T (A1.q) + s1 T + s2 T^2 + S0
//     reconstruction   T_hat = (D - Gs[E] - D0) / d (eq. 7),
//                      S_hat = A0.q + T_hat (A1.q) + s1 T_hat + s2 T_hat^2 + S0
// Without plain sides both run exactly the stress-hysteresis model, with its state. Real-time
// safe after construction: step() is noexcept and allocation-free.
#pragma once

#include <cstddef>
#include <optional>
#include <span>

#include "selfsense/models/reconstructor.hpp"
#include "selfsense/models/sample_status.hpp"
#include "selfsense/models/stress_hysteresis.hpp"
#include "selfsense/models/transducer_model.hpp"
#include "selfsense/operators/regressor_stream.hpp"

namespace selfsense::models {

class StressSidesForward final {
 public:
  // model.vectorial is required; model.sensor and model.actuator are the plain sides where it
  // has none (TransducerModel::is_valid).
  explicit StressSidesForward(const TransducerModel& model);
  StressSidesForward(const StressSidesForward&) = delete;
  StressSidesForward& operator=(const StressSidesForward&) = delete;
  StressSidesForward(StressSidesForward&&) = delete;
  StressSidesForward& operator=(StressSidesForward&&) = delete;
  ~StressSidesForward() = default;

  // D and S at field e [V/m] and stress t [Pa]; NaN for a channel neither part has.
  StressHysteresisForward::Output step(double e, double t) noexcept;

  // The stress-hysteresis part's state, then the plain sides'.
  [[nodiscard]] std::size_t state_size() const noexcept;
  void save_state(std::span<double> out) const noexcept;
  void restore_state(std::span<const double> in) noexcept;

  [[nodiscard]] const operators::RegressorStream& stream() const noexcept {
    return vectorial_.stream();
  }
  [[nodiscard]] operators::RegressorStream& stream() noexcept { return vectorial_.stream(); }
  [[nodiscard]] ForwardModel& plain() noexcept { return plain_; }
  [[nodiscard]] const ForwardModel& plain() const noexcept { return plain_; }

 private:
  StressHysteresisForward vectorial_;
  ForwardModel plain_;
};

class StressSidesReconstructor final {
 public:
  using Estimate = StressHysteresisReconstructor::Estimate;
  // Throws std::invalid_argument without a sensor side in either part, or with a plain sensor
  // side of zero stress coupling.
  explicit StressSidesReconstructor(const TransducerModel& model);
  StressSidesReconstructor(const StressSidesReconstructor&) = delete;
  StressSidesReconstructor& operator=(const StressSidesReconstructor&) = delete;
  StressSidesReconstructor(StressSidesReconstructor&&) = delete;
  StressSidesReconstructor& operator=(StressSidesReconstructor&&) = delete;
  ~StressSidesReconstructor() = default;

  Estimate step(double e, double d) noexcept;
  [[nodiscard]] bool has_strain() const noexcept { return has_strain_; }

  // The same step in phases where the sensor side is plain, so that a sensed-channel correction
  // can act between them (runtime_model.hpp): sensed_response(e) = Gs[E] + D0 advances the
  // plain sensor, T_hat = (D - response) / sensor_coupling(), and strain_at(e, T_hat) advances
  // the strain part. Only where plain_sensing().
  [[nodiscard]] bool plain_sensing() const noexcept { return plain_solve_.has_value(); }
  double sensed_response(double e) noexcept { return plain_solve_->sensed_response(e); }
  [[nodiscard]] double sensor_coupling() const noexcept {
    return plain_solve_->sensor()->coupling();
  }
  double strain_at(double e, double t) noexcept;

  // The stress-hysteresis part's state, then the plain sides'.
  [[nodiscard]] std::size_t state_size() const noexcept;
  void save_state(std::span<double> out) const noexcept;
  void restore_state(std::span<const double> in) noexcept;

  // The field's plays (for a hot swap's carry-over) and the plain sides' operators.
  [[nodiscard]] const operators::RegressorStream& stream() const noexcept;
  [[nodiscard]] operators::RegressorStream& stream() noexcept;
  // The plain sides' operators; null where the stress-hysteresis part has that side.
  [[nodiscard]] SideOperator* plain_sensor() noexcept;
  [[nodiscard]] const SideOperator* plain_sensor() const noexcept;
  [[nodiscard]] SideOperator* plain_actuator() noexcept;
  [[nodiscard]] const SideOperator* plain_actuator() const noexcept;

 private:
  // Exactly one of the first two: the stress-dependent sensor solves for T_hat, or the plain
  // sensor does and the stress-dependent actuator (strain_) gives S_hat.
  std::optional<StressHysteresisReconstructor> solve_{};
  std::optional<Reconstructor> plain_solve_{};
  std::optional<StressHysteresisForward> strain_{};
  ForwardModel plain_strain_;  // the plain actuator side, if any (S_hat from T_hat)
  bool has_strain_{false};
};

}  // namespace selfsense::models
