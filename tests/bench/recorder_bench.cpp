// The recorder: how many rows per second its writer thread formats and writes (sustained, with
// rotation and fdatasync as configured in the daemon), and what push() costs the loop while the
// writer works beside it.
//   cmake --build build --target recorder_bench && build/tests/bench/recorder_bench
// Files go to the temp directory and are removed.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

#include "selfsense/daemon/recorder.hpp"
#include "support/loop_samples.hpp"

namespace {

namespace fs = std::filesystem;
using selfsense::daemon::Recorder;
using selfsense::daemon::RecorderConfig;
using selfsense::runtime::LoopSample;
using selfsense::test::synthetic_sample;

constexpr double kTs = selfsense::test::kSampleTime;  // 20 kHz

fs::path scratch(const std::string& name) {
  fs::path dir =
      fs::temp_directory_path() / ("selfsense-bench-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

RecorderConfig config_in(const fs::path& dir) {
  RecorderConfig config;
  config.directory = dir;
  config.prefix = "bench";
  config.sample_time_s = kTs;
  config.rotate_bytes = std::size_t{64} << 20U;
  config.flush_period_ms = 500.0;
  config.flight.dump_on_fault = false;
  return config;
}

// Rows per second the writer sustains: 400 000 rows (20 s at 20 kHz) pushed as fast as the
// writer takes them, timed from the first push to the file closed and synced.
void BM_WriterRows(benchmark::State& state) {
  const fs::path dir = scratch("rows");
  constexpr std::int64_t kRows = 400'000;
  for (auto _ : state) {
    Recorder recorder(config_in(dir));
    recorder.start();
    recorder.start_file();
    for (std::int64_t k = 0; k < kRows; ++k) {
      while (recorder.queued() + 1 >= recorder.capacity())
        std::this_thread::yield();
      recorder.push(synthetic_sample(k));
    }
    recorder.stop_file();
    recorder.stop();
    if (recorder.counters().rows_written != kRows) state.SkipWithError("rows missing");
    state.PauseTiming();
    fs::remove_all(dir);
    fs::create_directories(dir);
    state.ResumeTiming();
  }
  state.SetItemsProcessed(state.iterations() * kRows);
  std::error_code ignored;
  fs::remove_all(dir, ignored);
}
BENCHMARK(BM_WriterRows)->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();

// push() as the loop sees it, one call at a time at 20 kHz while the writer formats and
// writes beside it. Each call is timed with steady_clock; clock_ns is what the clock alone costs
// and is included in the percentiles.
void BM_PushCost(benchmark::State& state) {
  const fs::path dir = scratch("push");
  Recorder recorder(config_in(dir));
  recorder.start();
  recorder.start_file();
  constexpr std::size_t kSamples = 100'000;  // 5 s at 20 kHz
  std::vector<double> ns;
  ns.reserve(kSamples);
  std::vector<double> clock_ns;
  clock_ns.reserve(kSamples);
  std::int64_t cycle = 0;
  for (auto _ : state) {
    ns.clear();
    clock_ns.clear();
    auto next = std::chrono::steady_clock::now();
    for (std::size_t i = 0; i < kSamples; ++i) {
      next += std::chrono::microseconds(50);
      while (std::chrono::steady_clock::now() < next) {
      }
      const LoopSample s = synthetic_sample(cycle++);
      const auto t0 = std::chrono::steady_clock::now();
      const bool ok = recorder.push(s);
      const auto t1 = std::chrono::steady_clock::now();
      const auto t2 = std::chrono::steady_clock::now();
      benchmark::DoNotOptimize(ok);
      ns.push_back(std::chrono::duration<double, std::nano>(t1 - t0).count());
      clock_ns.push_back(std::chrono::duration<double, std::nano>(t2 - t1).count());
    }
  }
  recorder.stop();
  const auto percentile = [](std::vector<double> v, double q) {
    std::sort(v.begin(), v.end());
    return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
  };
  state.counters["p50_ns"] = percentile(ns, 0.5);
  state.counters["p99_ns"] = percentile(ns, 0.99);
  state.counters["p99.9_ns"] = percentile(ns, 0.999);
  state.counters["max_ns"] = *std::max_element(ns.begin(), ns.end());
  state.counters["clock_p50_ns"] = percentile(clock_ns, 0.5);
  state.counters["dropped"] = static_cast<double>(recorder.counters().samples_dropped);
  std::error_code ignored;
  fs::remove_all(dir, ignored);
}
BENCHMARK(BM_PushCost)->Unit(benchmark::kMillisecond)->Iterations(1)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
