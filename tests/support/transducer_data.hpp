// Synthetic transducer recordings from a known model, for identification tests.
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

#include "selfsense/models/reconstructor.hpp"
#include "selfsense/operators/typical_stack.hpp"

namespace selfsense::test {

struct TransducerData {
  std::vector<double> e, t, d, s;
};

// The typical stack (hysteresis-creep on both sides) with couplings d = 3e-10 C/N and
// sE = 2e-11 1/Pa, in a remanent state (field up to 2 MV/m and back to the first sample of
// transducer_data, creep settled), driven by a modulated field and a slowly varying load.
inline models::TransducerModel typical_transducer(double ts) {
  operators::TypicalStackSize size;
  size.plays = 12;
  size.dead_zones = 3;
  size.eigenvalues = 4;
  models::TransducerModel m;
  m.structure = models::Structure::kHysteresisCreep;
  m.sample_time = ts;
  const std::vector<double> history{0.0, 2e6, 1e6};
  m.sensor =
      models::SideModel{operators::typical_stack_charge(size), {3e-10}, 0.0, 0.0, history, ts};
  m.actuator =
      models::SideModel{operators::typical_stack_strain(size), {2e-11}, 0.0, 0.0, history, ts};
  return m;
}

inline TransducerData transducer_data(const models::TransducerModel& truth, std::size_t n,
                                      double noise_share, std::uint64_t seed) {
  TransducerData out;
  models::ForwardModel plant(truth);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  const double ts = truth.sample_time;
  for (std::size_t k = 0; k < n; ++k) {
    const double time = static_cast<double>(k) * ts;
    const double e = 1e6 * (1.0 + 0.9 * std::sin(2 * std::numbers::pi * 1.0 * time) *
                                      std::cos(2 * std::numbers::pi * 0.11 * time));
    const double t = -1e7 * (1.0 + 0.8 * std::sin(2 * std::numbers::pi * 0.37 * time + 0.5));
    const models::ForwardModel::Output y = plant.step(e, t);
    out.e.push_back(e + noise_share * 2e6 * n01(rng));
    out.t.push_back(t);
    out.d.push_back(y.sensed + noise_share * 0.1 * n01(rng));
    out.s.push_back(y.strain);
  }
  return out;
}

}  // namespace selfsense::test
