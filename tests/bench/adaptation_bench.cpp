// Per-sample cost of self-sensing with online drift estimation against the plain runtime
// reconstruction, on the shipped 20 kHz preisach-creep model (config/models/sim.yaml).
//   cmake --build build --target adaptation_bench && build/tests/bench/adaptation_bench
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstddef>
#include <numbers>
#include <vector>

#include "selfsense/adaptation/adapted_reconstruction.hpp"
#include "selfsense/model_io/model_yaml.hpp"
#include "selfsense/models/runtime_model.hpp"

namespace {

using selfsense::models::TransducerModel;

const TransducerModel& model() {
  static const TransducerModel m =
      selfsense::models::load_model(SELFSENSE_SOURCE_DIR "/config/models/sim.yaml");
  return m;
}

// E: a 200 Hz sine of 0.8 MV/m about 1 MV/m at 20 kHz; D from the model itself (T = 0).
struct Signals {
  std::vector<double> e, d;
};

const Signals& signals() {
  static const Signals s = [] {
    Signals out;
    selfsense::models::Simulation sim(model());
    for (std::size_t k = 0; k < 4000; ++k) {
      const double t = static_cast<double>(k) * model().sample_time;
      const double e = 1e6 + 0.8e6 * std::sin(2.0 * std::numbers::pi * 200.0 * t);
      out.e.push_back(e);
      out.d.push_back(sim.step(e, 0.0).sensed);
    }
    return out;
  }();
  return s;
}

template <typename Model>
void run(benchmark::State& state, Model& m) {
  const Signals& s = signals();
  std::size_t k = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(m.step(s.e[k], s.d[k]));
    k = (k + 1) % s.e.size();
  }
}

void BM_Reconstruction(benchmark::State& state) {
  selfsense::models::Reconstruction rec(model());
  run(state, rec);
}
BENCHMARK(BM_Reconstruction);

void BM_AdaptedReconstruction(benchmark::State& state) {
  selfsense::adaptation::AdaptedReconstruction rec(model(),
                                                   selfsense::adaptation::DriftEstimatorConfig{});
  run(state, rec);
}
BENCHMARK(BM_AdaptedReconstruction);

}  // namespace

BENCHMARK_MAIN();
