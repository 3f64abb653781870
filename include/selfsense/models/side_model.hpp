// One side of a transducer model as identified (transducer_model.hpp):
//   y = Gamma[x] + sum_k g_k u_k + offset + quadratic * x^2
// Gamma a hysteresis-creep operator (operators/hysteresis_creep.hpp) with continuous-time creep
// eigenvalues, so the same side runs at any sample time; u_k inputs that enter linearly (the
// stress T, paper eq. 26-27). Identification fills it (identification/operator_fit.hpp); the
// runtime models run it.
#pragma once

#include <vector>

#include "selfsense/operators/hysteresis_creep.hpp"

namespace selfsense::models {

struct SideModel {
  operators::HysteresisCreep::Params op{};
  std::vector<double> linear_gains{};  // g_k
  double offset{0.0};
  double quadratic{0.0};          // y += quadratic * x^2 (electrostriction; set by the caller)
  std::vector<double> history{};  // input turning points before the first sample
  double sample_time{0.0};        // [s] of the recording it was fitted on
};

}  // namespace selfsense::models
