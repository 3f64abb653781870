// The CAN signal codec per call (include/selfsense/drivers/can/can_codec.hpp): what the bus thread
// spends per decoded signal and write() per encoded command. Figures, not a test
// (docs/drivers/can.md).
#include <benchmark/benchmark.h>

#include <array>
#include <cstdint>

#include "selfsense/drivers/can/can_codec.hpp"

namespace {

using selfsense::drivers::can::ByteOrder;
using selfsense::drivers::can::Signal;

void BM_CanDecode32(benchmark::State& state) {
  const Signal little{0, 32, ByteOrder::kLittle, true, 1e-9, 0.0};
  const Signal big{7, 32, ByteOrder::kBig, true, 1e-9, 0.0};
  const Signal& used = state.range(0) == 0 ? little : big;
  std::array<std::uint8_t, 8> data{0x12, 0x34, 0x56, 0x78, 0x9A, 0xBC, 0xDE, 0xF0};
  for (auto _ : state) {
    benchmark::DoNotOptimize(data);
    benchmark::DoNotOptimize(selfsense::drivers::can::decode(data, used));
  }
}
BENCHMARK(BM_CanDecode32)->Arg(0)->Arg(1)->ArgName("big");

void BM_CanEncode32(benchmark::State& state) {
  const Signal s{0, 32, ByteOrder::kLittle, true, 1.0, 0.0};
  std::array<std::uint8_t, 8> data{};
  double value = 1.25e6;
  for (auto _ : state) {
    benchmark::DoNotOptimize(value);
    benchmark::DoNotOptimize(selfsense::drivers::can::encode(data, s, value));
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_CanEncode32);

}  // namespace

BENCHMARK_MAIN();
