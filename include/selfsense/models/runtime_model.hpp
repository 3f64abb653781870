// The transducer model as the real-time loop, the tools and the diagnosis run it: one type for
// every structure (models/transducer_model.hpp), built from a model file's contents, at any loop
// rate, with a status per sample.
//
//   Reconstruction  self-sensing, from the measured drive and sensed channel (E and D for field
//                   drive, D and E for charge drive) to T_hat [Pa] and S_hat [-]
//   Simulation      forward, from the drive and the stress T to the sensed channel and S
//
// Any loop rate. The model's parameters are continuous-time (creep eigenvalues lambda [1/s];
// plays are rate independent), so a model identified at one sample time Ts_id runs at another
// Ts by discretising again: a_j = 1 - exp(-lambda_j Ts). rediscretised() says when that
// happened.
//
// A status per sample (models/sample_status.hpp). A sample whose inputs are not finite, or lie
// outside the identification range widened by `range_margin` of its span on each side, is
// rejected before it reaches the operators: they advance with the last accepted inputs held
// instead, so the play memory stays as it was (one spike of 10x full field would otherwise wipe
// the hysteresis memory) while the creep lags keep time with the loop. The estimate at the held
// inputs is returned with the rejecting status. Models without a recorded range (older files)
// check finiteness only.
//
// State with an identity (models/model_identity.hpp): saved into a SavedState sized once outside
// the loop, restored only into the same model.
//
// Hot swap: a replacement prepared outside the loop takes the running model's memory with
// adopt_state() at a cycle boundary (plays and lags where thresholds match, re-initialised from
// the last input otherwise); then the loop exchanges one pointer.
//
// Corrections a diagnosis added (channel_correction.hpp) run after the kernel: forward on both
// channels in Simulation; in Reconstruction the sensed channel's correction is inverted before
// the kernel (its delay moves to the drive) and the strain correction runs forward on S_hat
// (without its delay: a late bench sensor of S is not the actuator's). Their state follows the
// kernel's in a SavedState; a hot swap carries it over when the correction is the same and
// starts it afresh otherwise. The
// temperature they may use is set with set_temperature() (default: their reference).
//
// Real-time safe after construction: step(), save_state(), restore_state(), adopt_state() are
// noexcept and allocate nothing. Construction and make_saved_state() allocate.
#pragma once

#include <cstddef>
#include <memory>
#include <span>
#include <variant>
#include <vector>

#include "selfsense/models/channel_correction.hpp"
#include "selfsense/models/model_identity.hpp"
#include "selfsense/models/reconstructor.hpp"
#include "selfsense/models/sample_status.hpp"
#include "selfsense/models/stress_hysteresis.hpp"
#include "selfsense/models/stress_sides.hpp"
#include "selfsense/models/transducer_model.hpp"

namespace selfsense::models {

struct RuntimeOptions {
  double sample_time{0.0};   // [s] of the loop; 0: the model's own
  double range_margin{0.5};  // accepted: recorded range widened by this share of its span

  // sample_time >= 0 and finite, range_margin >= 0; names the field.
  [[nodiscard]] bool is_valid(std::string* why) const;
};

namespace detail {
struct ModelMemory;

// The last accepted pair of inputs (drive and sensed, or drive and stress).
struct HeldInputs {
  double first{0.0};
  double second{0.0};
  bool valid{false};
};

// The checks every runtime model makes before a sample reaches its operators.
class InputGate {
 public:
  InputGate() = default;
  InputGate(const std::optional<InputRange>& first, const std::optional<InputRange>& second,
            double margin) noexcept;
  [[nodiscard]] SampleStatus check(double first, double second) const noexcept;

 private:
  bool ranged_[2]{false, false};
  double lo_[2]{0.0, 0.0};
  double hi_[2]{0.0, 0.0};
};
}  // namespace detail

class Reconstruction final {
 public:
  struct Estimate {
    double stress{0.0};  // T_hat [Pa]
    double strain{0.0};  // S_hat [-]; NaN without an actuator side
    SampleStatus status{SampleStatus::kOk};
  };

  // Throws std::invalid_argument if the model cannot reconstruct (no sensor side, no stress
  // coupling) or the options are invalid.
  explicit Reconstruction(const TransducerModel& model, const RuntimeOptions& options = {});
  Reconstruction(const Reconstruction&) = delete;
  Reconstruction& operator=(const Reconstruction&) = delete;
  Reconstruction(Reconstruction&&) noexcept = default;
  Reconstruction& operator=(Reconstruction&&) noexcept = default;
  ~Reconstruction() = default;

  Estimate step(double drive, double sensed) noexcept;

  [[nodiscard]] const StatusCounts& counts() const noexcept { return counts_; }
  [[nodiscard]] const ModelIdentity& identity() const noexcept { return identity_; }
  [[nodiscard]] double sample_time() const noexcept { return sample_time_; }
  [[nodiscard]] double identified_sample_time() const noexcept { return identified_ts_; }
  [[nodiscard]] bool rediscretised() const noexcept { return sample_time_ != identified_ts_; }
  [[nodiscard]] bool has_strain() const noexcept;
  // [degC], for temperature terms of the corrections; held until set again.
  void set_temperature(double degc) noexcept { temperature_ = degc; }

  [[nodiscard]] SavedState make_saved_state() const;  // allocates
  // False (and nothing written) if `out` was not made for this model's state size.
  bool save_state(SavedState& out) const noexcept;
  RestoreResult restore_state(const SavedState& in) noexcept;
  // Hot swap: take the memory of the model running until now (header comment).
  void adopt_state(const Reconstruction& running) noexcept;

 private:
  using Affine = Reconstructor;
  using Vectorial = std::unique_ptr<StressSidesReconstructor>;

  void memory(detail::ModelMemory& out) const noexcept;
  Estimate kernel_step(double drive, double sensed) noexcept;
  Estimate plain_sensor_step(StressSidesReconstructor& v, double& x, double& y) noexcept;

  std::variant<Affine, Vectorial> impl_;
  detail::InputGate gate_{};
  ModelIdentity identity_{};
  double sample_time_{0.0};
  double identified_ts_{0.0};
  detail::HeldInputs held_{};  // the last accepted inputs
  Estimate last_{};
  StatusCounts counts_{};
  std::vector<double> scratch_{};  // sized once: adopt_state() builds the new state here
  std::optional<CorrectionStage> sensed_fix_{};
  std::optional<CorrectionStage> strain_fix_{};
  double temperature_{25.0};
  double sensed_coupling_{0.0};  // of the stress, for the corrections' response r = y - g T
  double strain_coupling_{0.0};
};

class Simulation final {
 public:
  struct Output {
    double sensed{0.0};  // D (field drive) or E (charge drive); NaN without a sensor side
    double strain{0.0};  // S; NaN without an actuator side
    SampleStatus status{SampleStatus::kOk};
  };

  // Throws std::invalid_argument on invalid options.
  explicit Simulation(const TransducerModel& model, const RuntimeOptions& options = {});
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;
  Simulation(Simulation&&) noexcept = default;
  Simulation& operator=(Simulation&&) noexcept = default;
  ~Simulation() = default;

  // stress: T [Pa] (0 for the free actuator).
  Output step(double drive, double stress) noexcept;
  // [degC], for temperature terms of the corrections; held until set again.
  void set_temperature(double degc) noexcept { temperature_ = degc; }

  [[nodiscard]] const StatusCounts& counts() const noexcept { return counts_; }
  [[nodiscard]] const ModelIdentity& identity() const noexcept { return identity_; }
  [[nodiscard]] double sample_time() const noexcept { return sample_time_; }
  [[nodiscard]] bool rediscretised() const noexcept { return sample_time_ != identified_ts_; }

  [[nodiscard]] SavedState make_saved_state() const;  // allocates
  bool save_state(SavedState& out) const noexcept;
  RestoreResult restore_state(const SavedState& in) noexcept;

 private:
  using Affine = ForwardModel;
  using Vectorial = std::unique_ptr<StressSidesForward>;

  Output kernel_step(double drive, double stress) noexcept;

  std::variant<Affine, Vectorial> impl_;
  detail::InputGate gate_{};
  ModelIdentity identity_{};
  double sample_time_{0.0};
  double identified_ts_{0.0};
  detail::HeldInputs held_{};  // the last accepted inputs
  Output last_{};
  StatusCounts counts_{};
  std::optional<CorrectionStage> sensed_fix_{};
  std::optional<CorrectionStage> strain_fix_{};
  double temperature_{25.0};
  double sensed_coupling_{0.0};  // of the stress, for the corrections' response r = y - g T
  double strain_coupling_{0.0};
};

}  // namespace selfsense::models
