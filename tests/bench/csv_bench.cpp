// Reading and writing a recording of 1e6 rows x 6 columns (t, E, D, S, T, temp), the size of
// 100 s at 10 kHz. The file is written once to the temp directory and removed at the end.
//   cmake --build build --target csv_bench && build/tests/bench/csv_bench
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <numbers>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "selfsense/io/recording.hpp"

namespace {

namespace fs = std::filesystem;
using selfsense::io::Recording;

constexpr std::size_t kRows = 1'000'000;

// Smooth signals with full-precision values, so every cell is 15-20 characters as in real data.
Recording make_recording() {
  std::vector<double> t(kRows);
  std::vector<double> e(kRows);
  std::vector<double> d(kRows);
  std::vector<double> s(kRows);
  std::vector<double> stress(kRows);
  std::vector<double> temp(kRows);
  constexpr double kDt = 1e-4;
  for (std::size_t i = 0; i < kRows; ++i) {
    const double time = static_cast<double>(i) * kDt;
    const double phase = 2.0 * std::numbers::pi * 3.0 * time;
    t[i] = time;
    e[i] = 1.5e6 * std::sin(phase);
    d[i] = 0.25 * std::sin(phase - 0.1) + 1e-3 * std::cos(7.0 * phase);
    s[i] = 1.2e-3 * std::sin(phase - 0.2);
    stress[i] = -2.0e6 * std::cos(phase);
    temp[i] = 25.0 + 0.5 * std::sin(1e-2 * phase);
  }
  Recording recording;
  recording.comments = {"selfsense csv benchmark", "sample rate 10 kHz"};
  recording.set_column("t", std::move(t));
  recording.set_column("E", std::move(e));
  recording.set_column("D", std::move(d));
  recording.set_column("S", std::move(s));
  recording.set_column("T", std::move(stress));
  recording.set_column("temp", std::move(temp));
  return recording;
}

void BM_ReadRecordingCsv(benchmark::State& state, const fs::path& path) {
  const auto bytes = static_cast<std::int64_t>(fs::file_size(path));
  for (auto _ : state) {
    Recording recording = selfsense::io::read_recording_csv(path);
    benchmark::DoNotOptimize(recording);
  }
  state.SetBytesProcessed(state.iterations() * bytes);
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(kRows));
}

void BM_WriteRecordingCsv(benchmark::State& state, const Recording& recording,
                          const fs::path& path) {
  for (auto _ : state) {
    selfsense::io::write_recording_csv(recording, path);
  }
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(fs::file_size(path)));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(kRows));
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;

  const std::string stem = "selfsense_csv_bench_" + std::to_string(::getpid());
  const fs::path input = fs::temp_directory_path() / (stem + "_in.csv");
  const fs::path output = fs::temp_directory_path() / (stem + "_out.csv");
  const Recording recording = make_recording();
  selfsense::io::write_recording_csv(recording, input);

  benchmark::RegisterBenchmark("read_recording_csv/1e6x6", BM_ReadRecordingCsv, input)
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("write_recording_csv/1e6x6", BM_WriteRecordingCsv, recording, output)
      ->Unit(benchmark::kMillisecond);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();

  std::error_code ignored;
  fs::remove(input, ignored);
  fs::remove(output, ignored);
  return 0;
}
