// Per-sample cost of the operators on the real-time path.
//   cmake --build build --target operator_bench && build/tests/bench/operator_bench
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "selfsense/operators/hysteresis_creep.hpp"
#include "selfsense/operators/linear_creep.hpp"
#include "selfsense/operators/modified_prandtl_ishlinskii.hpp"
#include "selfsense/operators/prandtl_ishlinskii.hpp"
#include "selfsense/operators/typical_stack.hpp"
#include "support/random_walk.hpp"

namespace {

using namespace selfsense::operators;  // NOLINT(google-build-using-namespace)

constexpr double kTs = 1e-4;  // 10 kHz loop

const std::vector<double>& field_signal() {
  static const std::vector<double> e = selfsense::test::random_walk(4096, 0.0, 2e6, 2e4, 3);
  return e;
}

TypicalStackSize workload_size() {
  TypicalStackSize size;
  size.plays = 32;
  size.dead_zones = 16;
  size.eigenvalues = 10;
  size.creep_plays = 0;
  return size;
}

// Runs `step` once per iteration on the next sample of the field signal.
template <typename Step>
void run(benchmark::State& state, Step step) {
  const std::vector<double>& e = field_signal();
  std::size_t k = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(step(e[k]));
    k = (k + 1) & (e.size() - 1);
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_PrandtlIshlinskii32(benchmark::State& state) {
  PrandtlIshlinskii h(typical_stack_strain(workload_size()).hysteresis);
  run(state, [&](double x) { return h.step(x); });
}
BENCHMARK(BM_PrandtlIshlinskii32);

void BM_ModifiedPrandtlIshlinskii32x16(benchmark::State& state) {
  const HysteresisCreep::Params p = typical_stack_strain(workload_size());
  ModifiedPrandtlIshlinskii gamma(PrandtlIshlinskii(p.hysteresis),
                                  DeadZoneSuperposition(p.superposition));
  run(state, [&](double x) { return gamma.step(x); });
}
BENCHMARK(BM_ModifiedPrandtlIshlinskii32x16);

void BM_LinearCreep10(benchmark::State& state) {
  LinearCreep creep({log_spaced_eigenvalues(1e4, 1e-3, 10), std::vector<double>(10, 0.01)}, kTs);
  run(state, [&](double x) { return creep.step(x); });
}
BENCHMARK(BM_LinearCreep10);

void BM_HysteresisCreep(benchmark::State& state) {
  HysteresisCreep op(typical_stack_strain(workload_size()), kTs);
  run(state, [&](double x) { return op.step(x); });
}
BENCHMARK(BM_HysteresisCreep);

void BM_HysteresisCreepInverse(benchmark::State& state) {
  const HysteresisCreep::Params p = typical_stack_strain(workload_size());
  HysteresisCreepCompensator feedforward(HysteresisCreep(p, kTs), 0.0, 2e6);
  run(state, [&](double x) { return feedforward.step(x * 6e-10); });
}
BENCHMARK(BM_HysteresisCreepInverse);

// The reconstruction workload of one control cycle: the sensor-side operator (E -> D), the
// actuator-side operator (E -> S) and the inverse compensator (desired S -> E). Arguments:
// creep elements on plays besides r = 0, and hinges per play (the preisach-creep structure;
// its inverse is solved numerically).
struct Workload {
  HysteresisCreep sensor;
  HysteresisCreep actuator;
  HysteresisCreepCompensator feedforward;
};

HysteresisCreep::Params hinged(HysteresisCreep::Params p, std::size_t per_play) {
  std::vector<double> r{0.0};
  r.insert(r.end(), p.hysteresis.thresholds.begin(), p.hysteresis.thresholds.end());
  for (const double threshold : r) {
    for (std::size_t k = 1; k <= per_play; ++k) {
      p.hinges.thresholds.push_back(threshold);
      p.hinges.levels.push_back(threshold + (2e6 - 2.0 * threshold) * static_cast<double>(k) /
                                                static_cast<double>(per_play + 1));
      p.hinges.weights.push_back(0.05 * p.hysteresis.linear_weight / static_cast<double>(k));
    }
  }
  return p;
}

Workload workload(const benchmark::State& state) {
  TypicalStackSize size = workload_size();
  size.creep_plays = static_cast<std::size_t>(state.range(0));
  const auto hinges = static_cast<std::size_t>(state.range(1));
  const HysteresisCreep::Params strain = hinged(typical_stack_strain(size), hinges);
  return {HysteresisCreep(hinged(typical_stack_charge(size), hinges), kTs),
          HysteresisCreep(strain, kTs),
          HysteresisCreepCompensator(HysteresisCreep(strain, kTs), 0.0, 2e6)};
}

void BM_ReconstructionWorkload(benchmark::State& state) {
  Workload w = workload(state);
  run(state, [&](double x) {
    return w.sensor.step(x) + w.actuator.step(x) + w.feedforward.step(x * 6e-10);
  });
}
BENCHMARK(BM_ReconstructionWorkload)
    ->Args({0, 0})
    ->Args({4, 0})
    ->Args({0, 3})
    ->Args({0, 7})
    ->ArgNames({"creep_plays", "hinges_per_play"});

// Tail latency: every one of kTimedSamples samples timed on its own with steady_clock, so the
// worst cases show (cache misses, interrupts, preemption on a shared core), not only the mean.
// Each sample's figure includes one clock read; `clock_ns` is the median of an empty timed
// sample, to subtract from the percentiles when comparing with the mean-only figures;
// `over_10us` counts the samples slower than 10 us (on a shared core: preempted, not the code).
constexpr std::size_t kTimedSamples = 1'000'000;

double percentile(std::vector<std::int64_t>& ns, double q) {
  const auto k = static_cast<std::size_t>(q * static_cast<double>(ns.size() - 1));
  std::nth_element(ns.begin(), ns.begin() + static_cast<std::ptrdiff_t>(k), ns.end());
  return static_cast<double>(ns[k]);
}

template <typename Step>
void run_timed(benchmark::State& state, Step step) {
  using Clock = std::chrono::steady_clock;
  const std::vector<double>& e = field_signal();
  std::vector<std::int64_t> ns(kTimedSamples);
  std::vector<std::int64_t> empty(kTimedSamples / 10);
  for (auto _ : state) {
    std::size_t k = 0;
    for (std::int64_t& sample_ns : ns) {
      const Clock::time_point t0 = Clock::now();
      benchmark::DoNotOptimize(step(e[k]));
      const Clock::time_point t1 = Clock::now();
      sample_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(t1 - t0).count();
      k = (k + 1) & (e.size() - 1);
    }
    for (std::int64_t& sample_ns : empty) {
      const Clock::time_point t0 = Clock::now();
      benchmark::ClobberMemory();
      sample_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - t0).count();
    }
  }
  double sum = 0.0;
  for (const std::int64_t v : ns)
    sum += static_cast<double>(v);
  state.counters["mean_ns"] = sum / static_cast<double>(ns.size());
  state.counters["p50_ns"] = percentile(ns, 0.5);
  state.counters["p99_ns"] = percentile(ns, 0.99);
  state.counters["p99.9_ns"] = percentile(ns, 0.999);
  state.counters["max_ns"] = static_cast<double>(*std::max_element(ns.begin(), ns.end()));
  state.counters["clock_ns"] = percentile(empty, 0.5);
  state.counters["over_10us"] = static_cast<double>(
      std::count_if(ns.begin(), ns.end(), [](std::int64_t v) { return v > 10'000; }));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(ns.size()));
}

void BM_ReconstructionWorkloadTail(benchmark::State& state) {
  Workload w = workload(state);
  run_timed(state, [&](double x) {
    return w.sensor.step(x) + w.actuator.step(x) + w.feedforward.step(x * 6e-10);
  });
}
BENCHMARK(BM_ReconstructionWorkloadTail)
    ->Args({0, 0})
    ->Args({4, 0})
    ->Args({0, 3})
    ->Args({0, 7})
    ->ArgNames({"creep_plays", "hinges_per_play"})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
