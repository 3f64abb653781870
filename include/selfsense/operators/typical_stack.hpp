// Operator parameters of a typical multilayer piezo stack (about 10 mm long, 15 um stroke and
// D near 0.1 C/m^2 at a full field of 2e6 V/m, 12 % hysteresis, creep of about 1.5 % of a step
// per decade of time). For demos, tests and benchmarks; real actuators are identified.
#pragma once

#include <cstddef>

#include "selfsense/operators/hysteresis_creep.hpp"

namespace selfsense::operators {

struct TypicalStackSize {
  std::size_t plays{16};       // play operators besides the linear term
  std::size_t dead_zones{4};   // upper dead zones of the superposition
  std::size_t eigenvalues{5};  // creep lags, log-spaced from 100 1/s to 0.01 1/s
  std::size_t creep_plays{0};  // creep elements on plays besides r = 0 (0: linear creep)
};

inline constexpr double kTypicalFieldMax = 2e6;  // V/m

// Actuator side: E [V/m] -> S [-].
[[nodiscard]] HysteresisCreep::Params typical_stack_strain(const TypicalStackSize& size = {});
// Sensor side: E [V/m] -> D [C/m^2].
[[nodiscard]] HysteresisCreep::Params typical_stack_charge(const TypicalStackSize& size = {});

}  // namespace selfsense::operators
