// Identification speed: a 1e6-sample recording, about 100 operator weights.
//   cmake --build build --target identification_bench && build/tests/bench/identification_bench
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "selfsense/identification/operator_fit.hpp"
#include "selfsense/identification/stress_hysteresis_fit.hpp"
#include "selfsense/operators/typical_stack.hpp"

namespace {

using selfsense::identification::fit_operator;
using selfsense::identification::OperatorStructure;

constexpr double kTs = 1e-4;

struct Recording {
  std::vector<double> e, t, d;
};

const Recording& recording() {
  static const Recording r = [] {
    Recording out;
    selfsense::operators::HysteresisCreep truth(selfsense::operators::typical_stack_charge(), kTs);
    std::mt19937_64 rng(4);
    std::normal_distribution<double> noise(0.0, 1e-5);
    constexpr std::size_t kSamples = 1'000'000;
    for (std::size_t k = 0; k < kSamples; ++k) {
      const double time = static_cast<double>(k) * kTs;
      const double e = 1e6 * (1.0 + 0.8 * std::sin(2 * std::numbers::pi * 2.0 * time) *
                                        std::cos(2 * std::numbers::pi * 0.13 * time));
      const double t = -1e7 * (1.0 + std::sin(2 * std::numbers::pi * 0.4 * time));
      out.e.push_back(e);
      out.t.push_back(t);
      out.d.push_back(truth.step(e) + 3e-10 * t + noise(rng));
    }
    return out;
  }();
  return r;
}

// 65 PI partial sums + 4 x 8 creep weights + stress + offset = 99 columns.
void BM_FitOperator1e6(benchmark::State& state) {
  const Recording& r = recording();
  OperatorStructure s;
  s.plays = 64;
  s.eigenvalues = 8;
  s.creep_plays = 3;
  s.dead_zones = static_cast<std::size_t>(state.range(0));
  s.estimate_history = state.range(1) != 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(fit_operator({r.e, {r.t}, r.d, kTs}, s));
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(r.e.size()));
}
BENCHMARK(BM_FitOperator1e6)
    ->ArgNames({"dead_zones", "history"})
    ->Args({0, 0})
    ->Args({0, 1})
    ->Args({4, 1})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(2);

// stress-hysteresis with 48 plays: 2 x 49 play columns + T, T^2, offset = 101 columns per
// side, the remanent-state search and its refinement included (D side only).
void BM_FitStressHysteresis1e6(benchmark::State& state) {
  const Recording& r = recording();
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        selfsense::identification::fit_stress_hysteresis(r.e, r.t, r.d, {}, kTs, 48));
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(r.e.size()));
}
BENCHMARK(BM_FitStressHysteresis1e6)->Unit(benchmark::kMillisecond)->Iterations(2);

}  // namespace

BENCHMARK_MAIN();
