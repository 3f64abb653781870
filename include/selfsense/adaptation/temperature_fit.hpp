// Fits a model's temperature coefficients (models/temperature_coefficients.hpp) on a recording
// with a temperature channel, such as a ramp, or on several recordings together, such as
// recordings at several fixed temperatures (issue 24 items 1 and 5, docs/adaptation.md
// "Temperature coefficients"). The model's operators stay as identified at the reference
// temperature; only how its parts scale with the temperature change is fitted.
//
// The model runs along the recording's field; per sample, with each side's response split into
// its linear part L and loop H (adapted_reconstruction.hpp's SideSplit), dtheta = temp -
// reference_degc [K], the measured stress T [Pa], D [C/m^2] and S [-]:
//   sensor:   D - y0_s - q_s E^2 - L_s - H_s - d_s T
//               = (a1 dtheta + a2 dtheta^2) L_s + (b1 dtheta + b2 dtheta^2) H_s
//                 + (c1 dtheta + c2 dtheta^2) d_s T
//   actuator: S - y0_a - q_a E^2 - L_a - H_a - s_a T   = the same with the actuator's parts
// Linear least squares per side in six coefficients (three with quadratic false, or where the
// temperature takes fewer than three levels: below, TemperatureFitResult::quadratic), each column
// scaled to unit norm, a ridge of 1e-9 of the diagonal against a column that vanishes (a stress
// that never moves). The result is the effective drift of the model's split, which is not
// exactly the plant's permittivity and loop (docs/adaptation.md, "the split is the floor").
//
// The sensor side's drift as the online estimator sees it (models::IncrementTemperature): the
// same model run, gated as the estimator gates (drift_estimator.hpp: an update where |delta E|
// reaches min_field_step_v_per_m within max_interval_s of the anchor, at the model's sample
// time), with delta x = x[k] - x[a] between anchor and update:
//   delta D - delta L_s - delta H_s - d_s delta T
//     = i_L dtheta delta L_s + i_H dtheta delta H_s + c0 d_s delta T + c1 dtheta d_s delta T
// least squares in four coefficients, the same scaling and ridge; increments.linear_per_k and
// loop_per_k are i_L and i_H (0, 0 with fewer than 100 updates).
//
// Offline: allocates, throws.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "selfsense/models/temperature_coefficients.hpp"
#include "selfsense/models/transducer_model.hpp"

namespace selfsense::adaptation {

struct TemperatureFitInput {
  std::span<const double> field;        // E [V/m]
  std::span<const double> sensed;       // D [C/m^2]
  std::span<const double> stress;       // T [Pa], measured on the bench
  std::span<const double> strain;       // S [-], measured on the bench
  std::span<const double> temperature;  // [degC]
};

struct TemperatureFitResult {
  models::TemperatureCoefficients coefficients{};
  double sensor_rms_before{0.0};    // RMS of the sensor side's residual, no coefficients [C/m^2]
  double sensor_rms_after{0.0};     // with them
  double actuator_rms_before{0.0};  // the actuator side's [-]
  double actuator_rms_after{0.0};
  std::size_t samples{0};     // finite samples used
  std::size_t increments{0};  // gated increments in the increment fit
  // The quadratic terms were fitted: asked for, and the temperature visits at least three of
  // the intervals of min_span_k width that split its range. Recordings at two temperatures
  // cannot tell dtheta^2 from dtheta (their small drifts alone would decide the split), so
  // they get the first order: each part's secant between the two.
  bool quadratic{false};
};

// Throws std::invalid_argument naming the reason: a model that is not field-driven with both
// sides (or vectorial, or with corrections), columns of different lengths, fewer than 100
// samples, or a temperature that spans less than min_span_k.
[[nodiscard]] TemperatureFitResult fit_temperature(const models::TransducerModel& model,
                                                   const TemperatureFitInput& in,
                                                   double reference_degc, bool quadratic = true,
                                                   double min_span_k = 2.0,
                                                   double min_field_step_v_per_m = 20.0e3,
                                                   double max_interval_s = 0.05);

// The same on several recordings: the model runs along each from its own start state (each
// recording's first sample, as for one), and the rows of all of them form one least-squares
// problem per side (and one of increments; no increment spans two recordings). The temperature
// must span min_span_k over the recordings together, so recordings each held at one
// temperature (25, 40, 55 degC) fit what a ramp over that range fits. The errors name the
// recording by its index (0-based).
[[nodiscard]] TemperatureFitResult fit_temperature(
    const models::TransducerModel& model, const std::vector<TemperatureFitInput>& recordings,
    double reference_degc, bool quadratic = true, double min_span_k = 2.0,
    double min_field_step_v_per_m = 20.0e3, double max_interval_s = 0.05);

}  // namespace selfsense::adaptation
