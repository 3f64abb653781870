// The plant configured as a stack under a large compressive preload (800 N) whose coupling,
// permittivity and loop size follow the stress, with sensor noise: the test bed of the
// stress-dependent models.
#pragma once

#include "selfsense/plant/config.hpp"

namespace selfsense::test {

inline plant::PlantConfig stressed_stack(double sample_rate_hz, double d_noise_std) {
  plant::PlantConfig c;
  c.sample_rate_hz = sample_rate_hz;
  c.hysteresis.enabled = true;
  c.stress.enabled = true;
  c.mechanics.enabled = false;
  c.mechanics.load_stiffness_n_per_m = 0.0;  // the force acts on the stack as applied
  c.mechanics.load_force_n = -800.0;
  c.sensors.e.noise_std = 200.0;
  c.sensors.d.noise_std = d_noise_std;
  return c;
}

}  // namespace selfsense::test
