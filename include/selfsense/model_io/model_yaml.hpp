// Transducer models as versioned YAML files (target selfsense::model_io; the math libraries
// know nothing of files).
//
//   selfsense_model: 2                   # format version (1 is read too)
//   structure: hysteresis-creep          # linear | permittivity | hysteresis | ...
//   sample_time_s: 1.0e-4
//   geometry: {layer_thickness_m, electrode_area_m2, layers, active_length_m, cross_section_m2}
//   input_range: {drive: [min, max], sensed: [min, max]}   # optional: the identification
//                                        # recording's range; the runtime rejects samples far out
//   sensor:                              # D = S[H[E] + K[E]] + coupling T + offset
//     coupling: 3.0e-10                  # (charge drive: E = ... of D)
//     offset: 0.0
//     quadratic: 0.0                     # Q x^2, electrostriction (charge drive); optional
//     history: [0.0, 2.0e6, 1.0e6]       # input turning points before the first sample
//     hysteresis: {linear_weight, thresholds: [...], weights: [...]}
//     superposition: {linear_weight, upper_thresholds, upper_weights,
//                     lower_thresholds, lower_weights}
//     creep: {thresholds, eigenvalues, weights}
//   actuator: {...}                      # S = ..., same keys; coupling is the compliance
//   vectorial:                           # structure stress-hysteresis instead of the sides:
//     thresholds: [0, ...]               #   D = base.q + T stress.q + linear T
//     history: [...]                     #       + quadratic T^2 + offset
//     creep: {rows: [0, ...], eigenvalues: [...]}   # optional: q holds creep lags too
//     stress_range: [min, max]           #   (stress_hysteresis.hpp); bracket of the solver
//     sensor: {base, stress, linear, quadratic, offset}
//     actuator: {base, stress, linear, quadratic, offset}
//   corrections:                         # physics added by `selfsense diagnose`, optional
//     sensed: {gain, offset, leakage_tau_s, delay_s, ...}   # (models/channel_correction.hpp)
//     strain: {gain, creep_eigenvalues, creep_weights, dynamics_frequency_hz, ...}
//   temperature:                         # optional, field drive: how the sides change with
//     reference_degc: 25.0               # temperature (models/temperature_coefficients.hpp),
//     sensor: {linear: [per_k, per_k2], loop: [...], coupling: [...]}   # fitted on a ramp
//     actuator: {linear: [...], loop: [...], coupling: [...]}           # recording
//   fit: {...}                           # free-form notes written by identify, not read back
//   complete: true                       # format 2: the last key; a file cut short lacks it
// Loading is strict: unknown keys, missing fields, wrong types and parameters that make an
// operator non-invertible are errors naming file, line and key path.
#pragma once

#include <filesystem>
#include <string>

#include "selfsense/models/transducer_model.hpp"

namespace selfsense::models {

inline constexpr int kModelFormatVersion = 2;        // what save_model writes
inline constexpr int kOldestModelFormatVersion = 1;  // 1: no `complete` key

// Throws io::YamlError ("M.yaml:12: sensor.hysteresis.weights[3]: ...").
[[nodiscard]] TransducerModel load_model(const std::filesystem::path& path);
[[nodiscard]] TransducerModel model_from_string(const std::string& text,
                                                const std::string& source = "<string>");

// Full precision: a saved model loads back bit-identical. `fit_notes` is a YAML mapping text
// (may be empty) stored under `fit`. Throws std::runtime_error if the file cannot be written.
void save_model(const TransducerModel& model, const std::filesystem::path& path,
                const std::string& fit_notes = {});
[[nodiscard]] std::string model_to_string(const TransducerModel& model,
                                          const std::string& fit_notes = {});

}  // namespace selfsense::models
