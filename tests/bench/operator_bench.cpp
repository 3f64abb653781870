// Per-sample cost of the operators on the real-time path.
//   cmake --build build --target operator_bench && build/tests/bench/operator_bench
#include <benchmark/benchmark.h>

#include <cstddef>
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
// actuator-side operator (E -> S) and the inverse compensator (desired S -> E).
void BM_ReconstructionWorkload(benchmark::State& state) {
  TypicalStackSize size = workload_size();
  size.creep_plays = static_cast<std::size_t>(state.range(0));
  HysteresisCreep sensor(typical_stack_charge(size), kTs);
  HysteresisCreep actuator(typical_stack_strain(size), kTs);
  HysteresisCreepCompensator feedforward(HysteresisCreep(typical_stack_strain(size), kTs), 0.0,
                                         2e6);
  run(state,
      [&](double x) { return sensor.step(x) + actuator.step(x) + feedforward.step(x * 6e-10); });
}
BENCHMARK(BM_ReconstructionWorkload)->Arg(0)->Arg(4)->ArgName("creep_plays");

}  // namespace

BENCHMARK_MAIN();
