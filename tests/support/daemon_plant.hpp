// The daemon's simulated bench in tests: a stack with hysteresis, creep and sensor noise,
// pushing against a load spring (a fifth of its stiffness) through a mass, and a model of it
// identified from an open-loop recording with an independent load variation.
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "selfsense/identification/transducer_fit.hpp"
#include "selfsense/plant/config.hpp"
#include "selfsense/plant/plant.hpp"

namespace selfsense::test {

inline plant::PlantConfig daemon_plant(double sample_rate_hz, double resonance_hz = 2000.0,
                                       double damping_ratio = 0.05) {
  plant::PlantConfig c;
  c.sample_rate_hz = sample_rate_hz;
  c.seed = 7;
  c.hysteresis.enabled = true;
  c.creep.enabled = true;
  c.creep.tau_s = {0.004, 0.03, 0.35, 2.8, 25.0};
  c.creep.s_weights = {0.012, 0.012, 0.015, 0.015, 0.018};
  c.creep.d_weights = {0.008, 0.008, 0.01, 0.01, 0.012};
  c.mechanics.enabled = true;
  c.mechanics.resonance_hz = resonance_hz;
  c.mechanics.damping_ratio = damping_ratio;
  c.mechanics.load_stiffness_n_per_m = 15e6;
  c.mechanics.load_force_n = -100.0;
  c.sensors.e.noise_std = 200.0;
  c.sensors.d.noise_std = 7e-6;
  return c;
}

// Open loop: field sweeps of many sizes and offsets and a load varying independently of it;
// the model of `structure` (hysteresis-creep unless said) identified on that recording.
inline models::TransducerModel identify_daemon_plant(
    const plant::PlantConfig& config, double seconds,
    models::Structure structure = models::Structure::kHysteresisCreep) {
  plant::Plant p(config);
  const double ts = 1.0 / config.sample_rate_hz;
  const auto n = static_cast<std::size_t>(seconds / ts);
  // Recorded at 1 kHz (every `decimate`-th sample): the model is rate independent and the loop
  // re-discretises it; the fit stays fast.
  const auto decimate = static_cast<std::size_t>(std::max(1.0, std::round(1e-3 / ts)));
  std::vector<double> e, d, s, t;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> level(0.05e6, 1.95e6);
  double target = 1e6;
  double from = 0.0;
  double segment_start = 0.0;
  double segment_len = 1.0;
  for (std::size_t k = 0; k < n; ++k) {
    const double time = static_cast<double>(k) * ts;
    if (time - segment_start >= segment_len) {  // a new ramp to a random level
      from = target;
      target = level(rng);
      segment_start = time;
      segment_len = 0.3 + 1.2 * std::uniform_real_distribution<double>(0.0, 1.0)(rng);
    }
    const double a = (time - segment_start) / segment_len;
    const double field = from + (target - from) * 0.5 * (1.0 - std::cos(std::numbers::pi * a));
    const double force = 150.0 * std::sin(2.0 * std::numbers::pi * 0.23 * time);
    const plant::StepOutput o = p.step({field, force, 25.0});
    if (k % decimate != 0) continue;
    e.push_back(o.e_meas_v_per_m);
    d.push_back(o.d_meas_c_per_m2);
    s.push_back(o.s);
    t.push_back(o.t_pa);
  }
  return identification::identify({e, d, t, s, ts * static_cast<double>(decimate)}, structure,
                                  identification::defaults_for(structure));
}

}  // namespace selfsense::test
