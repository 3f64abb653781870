// Per-sample cost of the simulated plant: clean stack and every effect on (all_effects.yaml
// without its file: the same switches set in code so the benchmark needs no I/O).
#include <benchmark/benchmark.h>

#include <vector>

#include "selfsense/plant/excitation.hpp"
#include "selfsense/plant/plant.hpp"

namespace {

using selfsense::plant::Plant;
using selfsense::plant::PlantConfig;
using selfsense::plant::StepInput;
using selfsense::plant::StepOutput;

PlantConfig all_effects() {
  PlantConfig c{};
  c.hysteresis.enabled = true;
  c.creep.enabled = true;
  c.permittivity.enabled = true;
  c.stress.enabled = true;
  c.temperature.enabled = true;
  c.mechanics.enabled = true;
  c.mechanics.load_force_n = -300.0;
  c.charge_amplifier.leakage_enabled = true;
  c.charge_amplifier.drift_enabled = true;
  c.amplifier.enabled = true;
  c.sensors.e = {1, 300.0, {true, 18, -1.0e6, 3.0e6}};
  c.sensors.d = {1, 2.0e-6, {true, 18, -0.05, 0.15}};
  return c;
}

std::vector<StepInput> inputs(double fs) {
  selfsense::plant::ExcitationConfig x{};
  x.temperature = {25.0, 40.0};
  x.load = {0.0, 200.0, 0.5};
  return selfsense::plant::make_excitation("mix", x, fs, 1).inputs();
}

void run_steps(benchmark::State& state, const PlantConfig& config) {
  const std::vector<StepInput> in = inputs(config.sample_rate_hz);
  Plant plant{config};
  std::size_t k = 0;
  for (auto _ : state) {
    const StepOutput o = plant.step(in[k]);
    benchmark::DoNotOptimize(o);
    k = (k + 1 == in.size()) ? 0 : k + 1;
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}

void BM_PlantStepClean(benchmark::State& state) {
  run_steps(state, PlantConfig{});
}
void BM_PlantStepAllEffects(benchmark::State& state) {
  run_steps(state, all_effects());
}

// A 1e6-sample recording in one batch, as `selfsense plant` generates it.
void BM_PlantRunMillionSamples(benchmark::State& state) {
  const PlantConfig config = all_effects();
  std::vector<StepInput> in = inputs(config.sample_rate_hz);
  in.resize(1000000, in.back());
  std::vector<StepOutput> out(in.size());
  for (auto _ : state) {
    Plant plant{config};
    plant.run(in, out);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(in.size()));
}

BENCHMARK(BM_PlantStepClean);
BENCHMARK(BM_PlantStepAllEffects);
BENCHMARK(BM_PlantRunMillionSamples)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
