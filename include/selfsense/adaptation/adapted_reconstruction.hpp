// Self-sensing with the drift of the sensor side estimated online (drift_estimator.hpp): the
// affine reconstruction (models/reconstructor.hpp) with its parameters scaled by the estimate,
// sample by sample. Field drive only; a model with diagnosed corrections or a stress-dependent
// (vectorial) model is refused by name.
//
// With epsilon, lambda the estimated changes of permittivity and loop, c = coupling_per_k
// (theta_eq - reference) and s = compliance_per_k (theta_eq - reference) (drift_estimator.hpp),
// per side y0 the offset, q the quadratic term and L, H the split of the operator's response
// (SideSplit below):
//   T_hat = (D - y0_s - q_s E^2 - (1 + epsilon) L_s - (1 + lambda) H_s) / ((1 + c) d_s)    [Pa]
//   S_hat = y0_a + q_a E^2 + (1 + c) L_a + (1 + lambda) H_a + (1 + s) s_a T_hat            [-]
// The plant's loop scale acts on both sides alike (so lambda is the actuator's too); the
// coupling d cannot be told from the stress by E and D, so it follows the equivalent temperature
// with its coefficient per K, and so does the actuator's linear part (d E).
//
// The mount: on a load spring the stress follows the field (more field, more strain, more
// load), so d' delta T is not noise but moves with delta E and would be learned as permittivity
// (measured on the daemon's bench, r = 0.21: epsilon -7 % while the stack warmed by 20 K). With
// the load's stiffness over the stack's, r = load_stiffness_ratio, the quasi-static stress of
// the mount is predicted from the model's free strain as drifted so far (the drift before this
// sample's update: c, lambda, s the coupling, loop and compliance changes),
// S_free = y0_a + q_a E^2 + (1 + c) L_a + (1 + lambda) H_a:
//   delta T = -kappa delta S,  delta S = delta S_free + (1 + s) s_a delta T,  kappa = r / s_a
//   =>  T_mount = -kappa / (1 + (1 + s) r) S_free                                          [Pa]
// and the estimator learns from D - (1 + c) d_s T_mount (constants cancel in its increments).
// (With the undrifted free strain and coupling the mount's growing share of D as the stack
// warms was read as a smaller permittivity change: docs/daemon.md, "Where the warming ramp's
// error comes from".) r = 0: the stress is taken as independent of the field
// (docs/adaptation.md).
//
// A measured temperature (set_temperature) replaces the estimate: the drift is read from the
// estimator's coefficients per K at that temperature; and when the model carries fitted
// temperature coefficients (model.temperature, models/temperature_coefficients.hpp,
// temperature_fit.hpp) the six scales come from them instead, per side, at dtheta = temp -
// reference:
//   T_hat = (D - y0_s - q_s E^2 - gL_s L_s - gH_s H_s) / (gc_s d_s)
//   S_hat = y0_a + q_a E^2 + gL_a L_a + gH_a H_a + gc_a s_a T_hat
// with g(dtheta) = 1 + per_k dtheta + per_k2 dtheta^2 of each part. Without a measured
// temperature the model's coefficients serve the estimate: their first-order terms replace the
// configured ones per K (the loop's tie, the equivalent temperature; reference_degc too), the
// sensor side keeps the learned (1 + epsilon) and (1 + lambda), and the coupling and the
// actuator's three scales are the polynomials at the equivalent temperature dtheta_eq, the root
// of g_L,s(dtheta) = 1 + epsilon nearest epsilon / per_k.
// When the coefficients carry the estimator's increments (models::IncrementTemperature, fitted
// on the estimator's own gated increments: the loop they see is not the levels'), the
// estimator learns with their tie i_H / i_L, its epsilon means dtheta_eq = epsilon / i_L, and
// all six scales, the sensor's too, are the level polynomials at dtheta_eq (docs/adaptation.md,
// "Levels and increments"); a measured temperature sets epsilon = i_L dtheta.
//
// With the thermal model on (config.thermal.enabled, thermal_model.hpp), after each sample the
// estimate is carried to the temperature the thermal law predicts for the next one, from the
// power of the measured E and D (a rejected sample brings none) and the present equivalent
// temperature theta:
//   estimator.carry(theta[k+1] - theta[k]),  theta[k+1] = thermal law (thermal_model.hpp)
// so the estimate cools with the stack on holds, where the estimator cannot learn; frozen, it
// holds. Its state (4 values) follows the estimator's in the saved state, and only then.
//
// A sample whose inputs are not finite or outside the identification range (widened by
// range_margin of its span) is rejected as models::Reconstruction rejects it: the operators
// advance with the last accepted inputs, the estimator learns nothing and drops its anchor.
//
// Real-time safe after construction: step(), save_state(), restore_state() are noexcept and
// allocate nothing.
#pragma once

#include <cstddef>
#include <optional>
#include <span>

#include "selfsense/adaptation/drift_estimator.hpp"
#include "selfsense/adaptation/thermal_model.hpp"
#include "selfsense/models/model_identity.hpp"
#include "selfsense/models/reconstructor.hpp"
#include "selfsense/models/runtime_model.hpp"
#include "selfsense/models/sample_status.hpp"
#include "selfsense/models/transducer_model.hpp"
#include "selfsense/operators/dead_zone_superposition.hpp"

namespace selfsense::adaptation {

// A side's response r = G[E] (without the offset y0) split into its linear capacitive part L
// and the loop H = r - L, read after the side's step_unloaded(E):
//   L_in = w0 E + sum_j c_0j z_0j     the PI's linear weight and the creep of E itself (the
//                                     lags on creep threshold 0)
//   y_in = S^-1[r]                    the superposition's input (PI, hinges and creep)
//   H = s0 (y_in - L_in),  L = r - H  the loop through the superposition's linear weight; the
//                                     dead zones' bending counts with the linear part
// (measured on the 25 -> 55 degC ramp with the recorded temperature: T_hat 0.71 % this way,
// 1.01 % sharing the superposition in proportion, 1.82 % with the bending in the loop;
// docs/adaptation.md).
// Construction allocates (the superposition's inverse); split() is real-time safe.
class SideSplit final {
 public:
  struct Parts {
    double linear{0.0};  // L
    double loop{0.0};    // H
  };
  explicit SideSplit(const models::SideOperator& side);
  [[nodiscard]] Parts split(const models::SideOperator& side, double field,
                            double response) const noexcept;

 private:
  operators::DeadZoneSuperposition inverse_shape_;
};

class AdaptedReconstruction final {
 public:
  struct Estimate {
    double stress{0.0};  // T_hat [Pa]
    double strain{0.0};  // S_hat [-]; NaN without an actuator side
    models::SampleStatus status{models::SampleStatus::kOk};
    // The model's D for the field path as identified (no drift), with the mount's predicted
    // stress: y0_s + q_s E^2 + L_s + H_s + d_s T_mount [C/m^2] (the health estimate's
    // reference loop, health_estimator.hpp).
    double predicted_sensed{0.0};
  };

  // sample_time 0: the model's own. Throws std::invalid_argument naming the reason if the
  // model cannot be adapted (charge drive, vectorial, corrections, no stress coupling) or the
  // configuration is invalid.
  AdaptedReconstruction(const models::TransducerModel& model, const DriftEstimatorConfig& config,
                        double sample_time = 0.0, double range_margin = 0.5);

  Estimate step(double field, double sensed) noexcept { return step(field, sensed, true); }
  // learn false: the sample is estimated but the estimator learns nothing from it and drops
  // its anchor (the loop's own rejection: a fault cause in the same cycle).
  Estimate step(double field, double sensed, bool learn) noexcept;
  // A sample that never arrived (a driver fault): the operators do not advance, the estimator
  // drops its anchor, so no increment spans the gap.
  void skip() noexcept { estimator_.drop_anchor(); }

  // The estimator's drift; with the model's coefficients, the equivalent temperature is where
  // the fitted permittivity polynomial reaches the learned epsilon (header comment).
  [[nodiscard]] Drift drift() const noexcept;
  [[nodiscard]] const DriftEstimator& estimator() const noexcept { return estimator_; }
  // A measured temperature [degC] replaces the estimate until the next set_temperature() or
  // clear_temperature() (header comment): the drift is set from the coefficients per K (with the
  // model's fitted coefficients epsilon and lambda are its sensor polynomials there, and the
  // reconstruction takes all six scales from them). Meanwhile the estimator learns nothing (its
  // anchor drops, the thermal model does not carry it): a sensor that fails leaves the estimate
  // at its last temperature. Not finite: ignored.
  void set_temperature(double degc) noexcept;
  // Back to the estimated drift, learning from the next samples on.
  void clear_temperature() noexcept { measured_degc_ = kNoTemperature; }
  // The model carries fitted temperature coefficients.
  [[nodiscard]] bool has_temperature_coefficients() const noexcept {
    return coefficients_.has_value();
  }
  void set_frozen(bool frozen) noexcept { estimator_.set_frozen(frozen); }
  [[nodiscard]] const models::StatusCounts& counts() const noexcept { return counts_; }
  [[nodiscard]] bool has_strain() const noexcept { return kernel_.actuator().has_value(); }

  // The feedforward's scales at the last sample (runtime::Controller::set_feedforward_scales):
  // with the actuator's split L_a, H_a there and the scales of the header comment,
  //   response = (gL_a L_a + gH_a H_a) / (L_a + H_a),   compliance = gc_a
  // the drifted actuator's operator response over the identified one, the inverse's input
  // scale; {1, 1} without an actuator side or where |L_a + H_a| is below 1e-3 of |L_a| + |H_a|.
  struct FeedforwardScales {
    double response{1.0};
    double compliance{1.0};
  };
  [[nodiscard]] FeedforwardScales feedforward_scales() const noexcept;

  // The thermal model, when it is on.
  [[nodiscard]] const std::optional<ThermalModel>& thermal() const noexcept { return thermal_; }

  // The kernel's operator state followed by the estimator's (and the thermal model's, when on).
  [[nodiscard]] std::size_t state_size() const noexcept;
  // False (nothing written or read) if the span's size is not state_size().
  bool save_state(std::span<double> out) const noexcept;
  bool restore_state(std::span<const double> in) noexcept;
  // With the model's identity (models/model_identity.hpp: its structure and parameter hash,
  // and this state's size, so a plain Reconstruction's state of the same model is refused as
  // kWrongSize): a restart resumes the learned drift only into the same model.
  [[nodiscard]] const models::ModelIdentity& identity() const noexcept { return identity_; }
  [[nodiscard]] models::SavedState make_saved_state() const;  // allocates
  bool save_state(models::SavedState& out) const noexcept;
  models::RestoreResult restore_state(const models::SavedState& in) noexcept;

 private:
  struct Tag {};
  AdaptedReconstruction(const models::TransducerModel& model, const DriftEstimatorConfig& config,
                        double range_margin, Tag /*unused*/);
  Estimate kernel_step(double field, double sensed, bool accepted) noexcept;
  // The six scales of the parts (header comment): sensor L, H, coupling; actuator L, H,
  // compliance.
  struct Scales {
    double sensor_linear, sensor_loop, sensor_coupling;
    double actuator_linear, actuator_loop, actuator_compliance;
  };
  [[nodiscard]] Scales scales(const Drift& dr) const noexcept;
  static constexpr double kNoTemperature = -1.0e300;

  models::Reconstructor kernel_;
  SideSplit sensor_split_;
  std::optional<SideSplit> actuator_split_{};
  DriftEstimator estimator_;
  std::optional<ThermalModel> thermal_{};
  models::detail::InputGate gate_{};
  models::detail::HeldInputs held_{};
  Estimate last_{};
  models::StatusCounts counts_{};
  models::ModelIdentity identity_{};
  SideSplit::Parts actuator_parts_{};  // L_a, H_a at the last sample
  double mount_ratio_{0.0};            // r
  double mount_kappa_{0.0};            // r / s_a [Pa per unit strain]
  std::optional<models::TemperatureCoefficients> coefficients_{};
  double measured_degc_{kNoTemperature};  // kNoTemperature: none
};

}  // namespace selfsense::adaptation
