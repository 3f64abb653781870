// The control law of the loop: one mode at a time, on the self-sensed S_hat and T_hat (no
// external sensor), producing the amplifier command as a field E [V/m].
//
//   position   r = shape(S_set);  u = PID_S(r, S_hat) + ff(r)          (ff: inverse model)
//   force      r = shape(T_set);  u = PID_T(sigma r, sigma T_hat)    (sigma: force_direction)
//   open-loop  r = shape(S_set);  u = ff(r)                            (inverse compensation only)
//   damping    u = ff(shape(S_set)) + K_damp[S_hat]                    (collocated PPF or velocity
//                                                                       feedback, paper 3.1/3.2)
//   then       v = notch/low-pass chain[u],  E = clamp(v, E_min, E_max)
// ff is the inverse of the model's actuator side at the static load T_0 (T_hat when armed),
// Gamma^-1[r - sE T_0 - S0] (operators/hysteresis_creep.hpp, input_for). Not at the current
// T_hat: through a load's mass and spring that would close a second, positive loop (more field,
// more compression, more field) that the resonance makes unstable; the PID corrects the load's
// changes. The inverse is evaluated on an
// operator whose memory follows the command actually applied (it advances with E after the
// limits every cycle, in every mode), so the inverse always starts from the actuator's real
// history; 0 when disabled. The PID tracks the applied command (after the chain and the
// limits), so its integrator never winds up against the amplifier's range.
//
// Bumpless: arm(S_hat, T_hat, E_now) starts the setpoint shapers at the measured state and the
// PIDs so that the first command equals E_now. A mode change is allowed while disarmed; while
// armed it is bumpless (the new mode starts from the measured state and the last command).
//
// Real-time safe after construction: step(), arm(), set_mode(), tune() are noexcept
// and allocate nothing.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>

#include "selfsense/control/damping_controller.hpp"
#include "selfsense/control/filter_chain.hpp"
#include "selfsense/control/pid.hpp"
#include "selfsense/control/setpoint_shaper.hpp"
#include "selfsense/models/side_model.hpp"
#include "selfsense/operators/hysteresis_creep.hpp"
#include "selfsense/runtime/loop_sample.hpp"

namespace selfsense::runtime {

struct ControllerConfig;

// The feedforward's inverse model: built outside the loop (construction allocates), exchanged
// into a running controller with Controller::swap_feedforward() (a model reload).
struct Feedforward {
  std::optional<operators::HysteresisCreep> inverse{};  // empty: no feedforward
  double compliance{0.0};                               // sE of the actuator side
  double strain_offset{0.0};
};

// The feedforward of `actuator` at `sample_time` [s] (empty when the configuration disables it
// or the model has no actuator side). Throws what the operator's construction throws.
[[nodiscard]] Feedforward make_feedforward(const ControllerConfig& config,
                                           const std::optional<models::SideModel>& actuator,
                                           double sample_time);

struct ControllerConfig {
  ControlMode mode{ControlMode::kPosition};
  control::Pid::Params position{};  // E [V/m] per unit strain
  control::Pid::Params force{};     // E [V/m] per Pa, on force_direction * T
  // Sign of dT/dE of the mount: -1 when the stack pushes against a load (more field, more
  // compression, T more negative), so that the force PID keeps positive gains.
  double force_direction{-1.0};
  control::SetpointShaper::Params position_shaper{};  // [1/s] slew of strain
  control::SetpointShaper::Params force_shaper{};     // [Pa/s]
  control::DampingController::Params damping{};       // on S_hat, E [V/m] per unit strain
  bool feedforward{true};  // inverse model in position, open-loop and damping modes
  std::array<control::BiquadCoefficients, control::FilterChain::kMaxSections> filters{};
  std::size_t filter_count{0};
  double command_min{0.0};  // E [V/m]
  double command_max{2e6};
};

// What a reload may change while armed (Controller::tune): the PID gains, the filter chain and
// the command limits.
struct Tuning {
  control::Pid::Gains position{};
  control::Pid::Gains force{};
  std::array<control::BiquadCoefficients, control::FilterChain::kMaxSections> filters{};
  std::size_t filter_count{0};
  double command_min{0.0};  // E [V/m]
  double command_max{2e6};
};

// The tuning part of a configuration.
[[nodiscard]] Tuning tuning_of(const ControllerConfig& config) noexcept;

class Controller final {
 public:
  // actuator: the model's actuator side (for the feedforward); nullopt: no feedforward.
  // Throws std::invalid_argument on invalid parameters, naming them.
  Controller(const ControllerConfig& config, const std::optional<models::SideModel>& actuator,
             double sample_time);

  // One cycle; the setpoint in the mode's unit (strain, or stress [Pa]).
  double step(double setpoint, double s_hat, double t_hat) noexcept;
  // Bumpless start at the measured state with the command now applied.
  void arm(double s_hat, double t_hat, double command) noexcept;
  void set_mode(ControlMode mode, double s_hat, double t_hat, double command) noexcept;
  // Gains, filters and command limits while running, all or nothing; false (nothing changed) if
  // any is invalid. Gains without an output bump (control::Pid::set_gains); the filter chain
  // by control::FilterChain::assign, changed and added sections settled at the last command;
  // the limits act from the next step (a command outside them is clamped there, and the PIDs
  // track the clamp as always).
  bool tune(const Tuning& tuning) noexcept;

  [[nodiscard]] ControlMode mode() const noexcept { return mode_; }
  [[nodiscard]] double shaped_setpoint() const noexcept { return shaped_; }
  [[nodiscard]] bool has_feedforward() const noexcept { return ff_.inverse.has_value(); }
  // Exchanges the feedforward with `next` (which then holds the old one, to be freed outside the
  // loop). The new inverse's memory starts settled at the command now applied: the old one's
  // plays cannot be carried over to other thresholds. No allocation (moves only).
  void swap_feedforward(Feedforward& next) noexcept;
  [[nodiscard]] std::size_t saturations() const noexcept { return saturations_; }
  // The stack's drift for the feedforward (adaptation::AdaptedReconstruction::
  // feedforward_scales(): the actuator's operator response and compliance as adapted, at a
  // measured temperature or from the estimated drift, over their values as identified). The
  // inverse is applied to
  //   (strain - compliance_scale s T_arm - y0) / response_scale
  // so the drifted actuator, response_scale times the identified operator, reaches the strain.
  // A scale that is not finite or outside [0.5, 2] is taken as 1. Real-time safe.
  void set_feedforward_scales(double response_scale, double compliance_scale) noexcept;
  // The scales in use (after the bound above) [1].
  [[nodiscard]] double feedforward_response_scale() const noexcept { return ff_response_scale_; }
  [[nodiscard]] double feedforward_compliance_scale() const noexcept {
    return ff_compliance_scale_;
  }

 private:
  double feedforward(double strain) noexcept;
  double law(double setpoint, double s_hat, double t_hat) noexcept;  // the mode's u
  double finish(double u) noexcept;  // chain, limits, PID tracking, inverse memory

  ControllerConfig config_;
  ControlMode mode_{ControlMode::kPosition};
  control::Pid position_;
  control::Pid force_;
  control::SetpointShaper position_shaper_;
  control::SetpointShaper force_shaper_;
  control::FilterChain chain_{};
  std::optional<control::DampingController> damping_{};
  Feedforward ff_{};       // the inverse's memory follows the applied E
  double ff_stress_{0.0};  // T_hat at arm: the feedforward's static load
  double ff_response_scale_{1.0};
  double ff_compliance_scale_{1.0};
  double shaped_{0.0};
  double last_command_{0.0};
  std::size_t saturations_{0};
};

}  // namespace selfsense::runtime
