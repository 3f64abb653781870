// Per-sample cost of the control laws on the real-time path.
//   cmake --build build --target control_bench && build/tests/bench/control_bench
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <vector>

#include "selfsense/control/damping_controller.hpp"
#include "selfsense/control/filter_chain.hpp"
#include "selfsense/control/filter_design.hpp"
#include "selfsense/control/pid.hpp"
#include "selfsense/control/setpoint_shaper.hpp"
#include "selfsense/control/wave_generator.hpp"

namespace {

using namespace selfsense::control;  // NOLINT(google-build-using-namespace)

constexpr double kTs = 5e-5;  // 20 kHz loop

// A measurement-like signal: a slow sine with a resonance and a little deterministic noise.
const std::vector<double>& signal() {
  static const std::vector<double> y = [] {
    std::vector<double> v(4096);
    for (std::size_t k = 0; k < v.size(); ++k) {
      const double t = static_cast<double>(k) * kTs;
      v[k] = 1e-3 * std::sin(2.0 * 3.14159 * 10.0 * t) +
             1e-5 * std::sin(2.0 * 3.14159 * 500.0 * t) +
             1e-7 * static_cast<double>((k * 7919) % 13);
    }
    return v;
  }();
  return y;
}

// Runs `step` once per iteration on the next sample of the signal.
template <typename Step>
void run(benchmark::State& state, Step step) {
  const std::vector<double>& y = signal();
  std::size_t k = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(step(y[k]));
    k = (k + 1) & (y.size() - 1);
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_Pid(benchmark::State& state) {
  Pid::Params p;
  p.gains = {200.0, 4e5, 0.02};
  p.derivative_filter_n = 10.0;
  p.output_min = 0.0;
  p.output_max = 2e6;
  p.tracking_time = 1e-3;
  Pid pid(p, kTs);
  run(state, [&](double y) { return pid.step(1e-3, y, 1e5); });
}
BENCHMARK(BM_Pid);

void BM_Biquad(benchmark::State& state) {
  Biquad notch_filter(notch({.frequency = 500.0, .quality = 5.0}, kTs));
  run(state, [&](double y) { return notch_filter.step(y); });
}
BENCHMARK(BM_Biquad);

void BM_FilterChainTwoNotchesAndLowPass(benchmark::State& state) {
  const std::array<BiquadCoefficients, 3> sections = {
      notch({.frequency = 500.0, .quality = 5.0}, kTs),
      notch({.frequency = 1500.0, .quality = 5.0}, kTs),
      low_pass(SecondOrderDesign{.frequency = 4000.0}, kTs)};
  FilterChain chain(sections);
  run(state, [&](double y) { return chain.step(y); });
}
BENCHMARK(BM_FilterChainTwoNotchesAndLowPass);

void BM_SetpointShaperSecondOrder(benchmark::State& state) {
  SetpointShaper shaper(
      {.slew_rate = 0.1, .filter = SetpointShaper::Filter::kSecondOrder, .time_constant = 1e-3},
      kTs);
  run(state, [&](double y) { return shaper.step(y); });
}
BENCHMARK(BM_SetpointShaperSecondOrder);

// Wave generators take no input; the signal only paces the loop the same way.
void BM_WaveGenerator(benchmark::State& state, WaveGenerator::Config config) {
  WaveGenerator wave(std::move(config), kTs);
  run(state, [&](double) { return wave.step(); });
}
using Shape = WaveGenerator::Shape;
BENCHMARK_CAPTURE(BM_WaveGenerator, Sine,
                  WaveGenerator::Config{.shape = Shape::kSine, .frequency = 1.0});
BENCHMARK_CAPTURE(BM_WaveGenerator, Triangle,
                  WaveGenerator::Config{.shape = Shape::kTriangle, .frequency = 1.0});
BENCHMARK_CAPTURE(BM_WaveGenerator, Square,
                  WaveGenerator::Config{.shape = Shape::kSquare, .frequency = 1.0});
BENCHMARK_CAPTURE(BM_WaveGenerator, Staircase10,
                  WaveGenerator::Config{.shape = Shape::kStaircase,
                                        .levels = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9},
                                        .dwell = 0.1});
BENCHMARK_CAPTURE(BM_WaveGenerator, Table1000Times,
                  WaveGenerator::Config{.shape = Shape::kTable,
                                        .table_values = std::vector<double>(1000, 1.0),
                                        .table_times = [] {
                                          std::vector<double> t(1000);
                                          for (std::size_t i = 0; i < t.size(); ++i)
                                            t[i] = 1e-3 * static_cast<double>(i * i);
                                          return t;
                                        }()});
BENCHMARK_CAPTURE(BM_WaveGenerator, Table1000FixedStep,
                  WaveGenerator::Config{.shape = Shape::kTable,
                                        .table_values = std::vector<double>(1000, 1.0),
                                        .table_dt = 1e-3});

void BM_DampingPpf(benchmark::State& state) {
  DampingController ppf({.gain = 0.5, .frequency = 500.0, .damping = 0.3}, kTs);
  run(state, [&](double y) { return ppf.step(y); });
}
BENCHMARK(BM_DampingPpf);

void BM_DampingVelocity(benchmark::State& state) {
  DampingController velocity(
      {.law = DampingController::Law::kVelocity, .gain = 1e-4, .frequency = 5000.0}, kTs);
  run(state, [&](double y) { return velocity.step(y); });
}
BENCHMARK(BM_DampingVelocity);

// The loop's control law in one: wave -> shaper -> PID (+ feedforward) -> two notches + low-pass.
void BM_PositionLoopLaw(benchmark::State& state) {
  WaveGenerator wave({.shape = Shape::kSine, .amplitude = 5e-4, .offset = 7e-4, .frequency = 1.0},
                     kTs);
  SetpointShaper shaper({.slew_rate = 0.1}, kTs);
  Pid::Params p;
  p.gains = {200.0, 4e5, 0.0};
  p.output_min = 0.0;
  p.output_max = 2e6;
  p.tracking_time = 1e-3;
  Pid pid(p, kTs);
  const std::array<BiquadCoefficients, 3> sections = {
      notch({.frequency = 500.0, .quality = 5.0}, kTs),
      notch({.frequency = 1500.0, .quality = 5.0}, kTs),
      low_pass(SecondOrderDesign{.frequency = 4000.0}, kTs)};
  FilterChain chain(sections);
  run(state, [&](double y) { return chain.step(pid.step(shaper.step(wave.step()), y, 1e5)); });
}
BENCHMARK(BM_PositionLoopLaw);

}  // namespace

BENCHMARK_MAIN();
