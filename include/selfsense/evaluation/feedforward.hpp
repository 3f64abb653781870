// Inverse compensation (`selfsense feedforward`; the paper's reference [11]): from a desired
// strain trajectory, the field that makes the modelled actuator follow it,
//   E = Ga^-1[S_desired - sE * T - S0]
// with the hysteresis-creep compensator, limited to the amplifier's field range.
#pragma once

#include <cstddef>
#include <string>

#include "selfsense/io/recording.hpp"
#include "selfsense/models/transducer_model.hpp"

namespace selfsense::evaluation {

struct FeedforwardRun {
  io::Recording recording{};  // t, E, S_desired; u where the model has a geometry
  std::size_t limited{0};     // samples limited to the field range
};

// The trajectory names the strain to follow (S, or x with the model's geometry) and may name T;
// its sample time must be the model's (within 1 %). Throws std::invalid_argument when the model
// has no field-driven actuator side and io::RecordingError for an unusable trajectory, naming
// model_source or trajectory_source.
[[nodiscard]] FeedforwardRun feedforward(const models::TransducerModel& model,
                                         const io::Recording& trajectory, double field_min,
                                         double field_max, const std::string& model_source,
                                         const std::string& trajectory_source);

}  // namespace selfsense::evaluation
