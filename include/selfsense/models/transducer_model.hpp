// Transducer models of the paper's section 3 in one form, and their identification.
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

#include "selfsense/identification/fit_quality.hpp"
#include "selfsense/identification/operator_fit.hpp"
#include "selfsense/models/geometry.hpp"
#include "selfsense/models/stress_hysteresis.hpp"

namespace selfsense::models {

enum class Structure {
  kLinear,
  kPermittivity,
  kHysteresis,
  kHysteresisCreep,
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

// One side of the transducer: y = G[x] + coupling * T + offset, as fitted (OperatorModel with
// the stress as its only linear input; coupling 0 when the recording had no T).
using SideModel = identification::OperatorModel;

struct TransducerModel {
  Structure structure{Structure::kLinear};
  double sample_time{0.0};              // [s]
  std::optional<SideModel> sensor{};    // x -> D (field drive) or x -> E (charge drive)
  std::optional<SideModel> actuator{};  // x -> S
  std::optional<StressHysteresisModel> vectorial{};  // stress-hysteresis instead of the sides
  std::optional<Geometry> geometry{};                // for terminal quantities

  [[nodiscard]] Drive drive() const noexcept { return drive_of(structure); }
  // The operator parameters and couplings are valid and the sample times agree.
  [[nodiscard]] bool is_valid(std::string* why) const;
};

// Sizes of the operators an identification uses; defaults per structure (defaults_for).
struct IdentificationOptions {
  std::size_t plays{0};
  std::size_t eigenvalues{0};
  std::size_t creep_plays{0};
  std::size_t dead_zones{0};
  bool estimate_history{true};
  double fastest_eigenvalue{0.0};  // [1/s]; 0: from the sample time (OperatorStructure)
  double slowest_eigenvalue{0.0};  // [1/s]; 0: from the duration
};
[[nodiscard]] IdentificationOptions defaults_for(Structure s) noexcept;

// Recorded signals in field quantities. drive is E (field drive) or D (charge drive), sensed
// the other one. Empty sensed: no sensor side; empty strain: no actuator side; empty stress:
// the free actuator (T = 0, couplings not identifiable, so no reconstruction of T).
struct TransducerSignals {
  std::span<const double> drive{};
  std::span<const double> sensed{};
  std::span<const double> stress{};
  std::span<const double> strain{};
  double sample_time{0.0};
};

// Fits the sides the signals allow. Throws std::invalid_argument on unusable signals (no drive,
// neither sensed nor strain, mismatched lengths).
[[nodiscard]] TransducerModel identify(const TransducerSignals& signals, Structure structure,
                                       const IdentificationOptions& options);

}  // namespace selfsense::models
