// Per-sample evaluation of a transducer model: forward (simulation) and reconstruction
// (self-sensing). Both are real-time safe after construction: step() is O(n), noexcept and
// allocation-free; the state can be saved into and restored from caller-owned buffers.
//
// With one side written y = G[x] + c * T + y0 (transducer_model.hpp):
//   forward:         y = G[x] + c * T + y0
//   reconstruction:  T_hat = (y_measured - G_s[x] - y0_s) / c_s        (eq. 7, 20, 30)
//                    S_hat = G_a[x] + c_a * T_hat + y0_a                (eq. 8, 21, 31)
// x is E for field drive and D for charge drive; y the other one.
#pragma once

#include <optional>
#include <span>

#include "selfsense/models/transducer_model.hpp"
#include "selfsense/operators/hysteresis_creep.hpp"

namespace selfsense::models {

// One side as a running operator.
class SideOperator final {
 public:
  explicit SideOperator(const SideModel& model);
  // G[x] + y0 + quadratic x^2 (advances the operator).
  double step_unloaded(double x) noexcept { return op_.step(x) + offset_ + quadratic_ * x * x; }
  [[nodiscard]] double coupling() const noexcept { return coupling_; }
  [[nodiscard]] double offset() const noexcept { return offset_; }  // y0
  [[nodiscard]] double quadratic() const noexcept { return quadratic_; }
  [[nodiscard]] const operators::HysteresisCreep& op() const noexcept { return op_; }
  [[nodiscard]] operators::HysteresisCreep& op() noexcept { return op_; }

 private:
  operators::HysteresisCreep op_;
  double coupling_{0.0};
  double offset_{0.0};
  double quadratic_{0.0};
};

// Saves and restores the states of up to two sides into one caller-owned buffer.
class ModelState {
 public:
  [[nodiscard]] static std::size_t size(const std::optional<SideOperator>& a,
                                        const std::optional<SideOperator>& b) noexcept;
  static void save(const std::optional<SideOperator>& a, const std::optional<SideOperator>& b,
                   std::span<double> out) noexcept;
  static void restore(std::optional<SideOperator>& a, std::optional<SideOperator>& b,
                      std::span<const double> in) noexcept;
};

class ForwardModel final {
 public:
  struct Output {
    double sensed{0.0};  // D (field drive) or E (charge drive); NaN without a sensor side
    double strain{0.0};  // NaN without an actuator side
  };
  explicit ForwardModel(const TransducerModel& model);
  Output step(double drive, double stress) noexcept;
  [[nodiscard]] std::optional<SideOperator>& sensor() noexcept { return sensor_; }
  [[nodiscard]] std::optional<SideOperator>& actuator() noexcept { return actuator_; }
  [[nodiscard]] const std::optional<SideOperator>& sensor() const noexcept { return sensor_; }
  [[nodiscard]] const std::optional<SideOperator>& actuator() const noexcept { return actuator_; }

  [[nodiscard]] std::size_t state_size() const noexcept;
  void save_state(std::span<double> out) const noexcept;
  void restore_state(std::span<const double> in) noexcept;

 private:
  std::optional<SideOperator> sensor_{};
  std::optional<SideOperator> actuator_{};
};

class Reconstructor final {
 public:
  struct Estimate {
    double stress{0.0};  // T_hat [Pa]
    double strain{0.0};  // S_hat [-]; NaN without an actuator side
  };
  // Throws std::invalid_argument if the model has no sensor side or a zero sensor coupling
  // (then the measured charge says nothing about stress).
  explicit Reconstructor(const TransducerModel& model);
  Estimate step(double drive, double sensed) noexcept {
    return finish(drive, sensed, sensed_response(drive));
  }
  // The same step in two phases, for a sensed-channel correction that reads the sensor's
  // response to the drive alone (creep of that response, channel_correction.hpp):
  // sensed_response(x) = G_s[x] + y0_s advances the sensor operator; finish() takes the measured
  // y and that response and advances the actuator side.
  double sensed_response(double drive) noexcept { return sensor_->step_unloaded(drive); }
  Estimate finish(double drive, double sensed, double response) noexcept;
  [[nodiscard]] std::optional<SideOperator>& sensor() noexcept { return sensor_; }
  [[nodiscard]] std::optional<SideOperator>& actuator() noexcept { return actuator_; }
  [[nodiscard]] const std::optional<SideOperator>& sensor() const noexcept { return sensor_; }
  [[nodiscard]] const std::optional<SideOperator>& actuator() const noexcept { return actuator_; }

  [[nodiscard]] std::size_t state_size() const noexcept;
  void save_state(std::span<double> out) const noexcept;
  void restore_state(std::span<const double> in) noexcept;

 private:
  std::optional<SideOperator> sensor_{};
  std::optional<SideOperator> actuator_{};
};

}  // namespace selfsense::models
