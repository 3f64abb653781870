// Transducer models of the paper's section 3 in one form (identified by
// identification/transducer_fit.hpp, run per sample by models/runtime_model.hpp).
//
// Field drive (E imposed; eq. 5-15, 26-31):
//   D = Gs[E] + d * T + D0          sensor side
//   S = Ga[E] + sE * T + S0         actuator side
// Charge drive (D imposed; Jones and Garcia, eq. 16-21):
//   E = Gs[D] + g' * T + E0         (g' = -g of eq. 18)
//   S = Ga[D] + sD * T + Q * D^2 + S0   (Q: electrostriction, the butterfly loops past the
//                                        coercive field; 0 for field drive)
// G = S[H + K] is a hysteresis-creep operator (operators::HysteresisCreep); each structure fixes
// which of its parts exist:
//   linear            G = w0 * x                               (eq. 5-8)
//   permittivity      sensor G = piecewise linear eps(E) * E   (eq. 9-13), actuator linear
//   hysteresis        G = modified PI                          (eq. 14-15)
//   hysteresis-creep  G = modified PI + creep                  (eq. 26-31)
//   preisach-creep    G = modified PI with hinges on its plays + creep: the Preisach class
//                     (operators/play_hinges.hpp), minor loops that change with their offset
//   charge-drive      sensor E = modified PI of D, actuator S linear in D (eq. 18-19)
//   stress-hysteresis coupling, permittivity and loop size depend on T (section 3.3, the
//                     vectorial case): StressHysteresisModel, reconstructed numerically
// Reconstruction (self-sensing) inverts the sensor side for T in closed form (eq. 7, 20, 30)
// and feeds it to the actuator side (eq. 8, 21, 31): see Reconstructor.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "selfsense/models/channel_correction.hpp"
#include "selfsense/models/geometry.hpp"
#include "selfsense/models/side_model.hpp"
#include "selfsense/models/stress_hysteresis.hpp"
#include "selfsense/models/temperature_coefficients.hpp"

namespace selfsense::models {

enum class Structure {
  kLinear,
  kPermittivity,
  kHysteresis,
  kHysteresisCreep,
  kPreisachCreep,
  kChargeDrive,
  kStressHysteresis
};
enum class Drive { kField, kCharge };

[[nodiscard]] std::string_view to_string(Structure s) noexcept;
// Accepts the contract names ("hysteresis-creep"); nullopt otherwise.
[[nodiscard]] std::optional<Structure> parse_structure(std::string_view name) noexcept;
[[nodiscard]] Drive drive_of(Structure s) noexcept;
// All structure names, for messages: "linear, permittivity, ...".
[[nodiscard]] std::string structure_names();

// The range a channel covered in the identification recording: the runtime models reject
// samples far outside it (models/runtime_model.hpp) instead of letting a spike wipe the
// hysteresis memory.
struct InputRange {
  double min{0.0};
  double max{0.0};
  [[nodiscard]] double span() const noexcept { return max - min; }
};

struct TransducerModel {
  Structure structure{Structure::kLinear};
  double sample_time{0.0};              // [s]
  std::optional<SideModel> sensor{};    // x -> D (field drive) or x -> E (charge drive)
  std::optional<SideModel> actuator{};  // x -> S
  std::optional<StressHysteresisModel> vectorial{};  // stress-hysteresis instead of the sides
  std::optional<Geometry> geometry{};                // for terminal quantities
  std::optional<InputRange> drive_range{};           // x: E (field drive) or D (charge drive)
  std::optional<InputRange> sensed_range{};          // y: D (field drive) or E (charge drive)
  // Physics a diagnosis added after the sides (channel_correction.hpp); none in identified
  // models.
  std::optional<ChannelCorrection> sensed_correction{};
  std::optional<ChannelCorrection> strain_correction{};
  // How the sides change with temperature (temperature_coefficients.hpp), fitted on a ramp
  // recording; field drive only. Used where the temperature is measured
  // (adaptation/adapted_reconstruction.hpp); the plain runtime models ignore it, and it is not
  // part of the parameter hash (it does not change the operators' state).
  std::optional<TemperatureCoefficients> temperature{};

  [[nodiscard]] Drive drive() const noexcept { return drive_of(structure); }
  // The operator parameters and couplings are valid and the sample times agree.
  [[nodiscard]] bool is_valid(std::string* why) const;
};

// The model says something about the stress from the sensed channel: a stress-hysteresis sensor
// side, or a plain sensor side with a non-zero stress coupling (Reconstruction needs one).
[[nodiscard]] bool can_reconstruct(const TransducerModel& model) noexcept;

}  // namespace selfsense::models
