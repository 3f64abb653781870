// WaveGenerator: exact timing over 1e7 samples, shapes, repeats, tables, frequency changes.
#include "selfsense/control/wave_generator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

namespace selfsense::control {
namespace {

constexpr double kTs = 1.0 / 20000.0;  // 20 kHz
using Shape = WaveGenerator::Shape;

double sine_at(double p) {
  return std::sin(2.0 * std::numbers::pi * p);
}

TEST(WaveGenerator, SineHasNoDriftOver1e7Samples) {
  // 1 kHz at 20 kHz: 20 samples per period; after 1e7 samples exactly 5e5 periods.
  WaveGenerator wave({.shape = Shape::kSine, .frequency = 1000.0}, kTs);
  EXPECT_EQ(wave.period_samples(), 20.0);
  const std::int64_t n = 10'000'000;
  for (std::int64_t k = 0; k < n; ++k) {
    const double expected = sine_at(static_cast<double>(k % 20) / 20.0);
    const double w = wave.step();
    if (w != expected) FAIL() << "sample " << k << ": " << w << " != " << expected;
  }
  EXPECT_EQ(wave.cycles(), 5e5);
}

TEST(WaveGenerator, SquarePeriodCountIsExactOver1e7Samples) {
  WaveGenerator wave({.shape = Shape::kSquare, .amplitude = 2.0, .frequency = 1000.0}, kTs);
  std::int64_t rising = 0;
  std::int64_t high = 0;
  double previous = -2.0;
  for (std::int64_t k = 0; k < 10'000'000; ++k) {
    const double w = wave.step();
    if (w > 0.0) ++high;
    if (w > 0.0 && previous < 0.0) ++rising;
    previous = w;
  }
  EXPECT_EQ(rising, 500'000);
  EXPECT_EQ(high, 5'000'000);
}

TEST(WaveGenerator, PeriodOfAFractionalNumberOfSamplesDoesNotDrift) {
  // 3 Hz at 20 kHz: 6666.67 samples per period; the exact position is (3 k mod 20000) / 20000.
  WaveGenerator wave({.shape = Shape::kSine, .frequency = 3.0}, kTs);
  double worst = 0.0;
  for (std::int64_t k = 0; k < 10'000'000; ++k) {
    const double exact = sine_at(static_cast<double>((3 * k) % 20000) / 20000.0);
    worst = std::max(worst, std::abs(wave.step() - exact));
  }
  EXPECT_LT(worst, 1e-9);
  EXPECT_NEAR(wave.cycles(), 1500.0, 1e-9);
}

TEST(WaveGenerator, TriangleAndSquareShapesWithAmplitudeOffsetAndPhase) {
  const WaveGenerator::Config base{
      .shape = Shape::kTriangle, .amplitude = 2.0, .offset = 1.0, .frequency = 2500.0};  // P = 8
  WaveGenerator triangle(base, kTs);
  const std::vector<double> unit = {0.0, 0.5, 1.0, 0.5, 0.0, -0.5, -1.0, -0.5};
  for (int cycle = 0; cycle < 3; ++cycle) {
    for (const double u : unit)
      EXPECT_DOUBLE_EQ(triangle.step(), 1.0 + 2.0 * u);
  }
  WaveGenerator::Config shifted = base;
  shifted.shape = Shape::kSine;
  shifted.phase = 0.25;  // starts at the crest
  WaveGenerator sine(shifted, kTs);
  EXPECT_DOUBLE_EQ(sine.step(), 3.0);
  shifted.shape = Shape::kSquare;
  shifted.phase = 0.5;  // starts low
  WaveGenerator square(shifted, kTs);
  EXPECT_EQ(square.step(), -1.0);
}

TEST(WaveGenerator, RepeatCountThenHoldsTheEndValue) {
  WaveGenerator wave({.shape = Shape::kSine, .offset = 0.5, .frequency = 1000.0, .repeats = 3},
                     kTs);
  for (int k = 0; k < 60; ++k) {
    EXPECT_FALSE(wave.done()) << k;
    wave.step();
  }
  EXPECT_FALSE(wave.done());
  const double held = wave.step();
  EXPECT_TRUE(wave.done());
  EXPECT_NEAR(held, 0.5, 1e-12);
  for (int k = 0; k < 100; ++k)
    EXPECT_EQ(wave.step(), held);
  wave.restart();
  EXPECT_FALSE(wave.done());
  EXPECT_EQ(wave.step(), 0.5);
}

TEST(WaveGenerator, StaircasePlaysItsLevelsForTheirDwell) {
  // Dwell 0.15 ms = 3 samples per level; twice; then the last level holds.
  WaveGenerator wave({.shape = Shape::kStaircase,
                      .amplitude = 1.0,
                      .offset = 10.0,
                      .repeats = 2,
                      .levels = {0.0, 1.0, -2.0},
                      .dwell = 0.15e-3},
                     kTs);
  const std::vector<double> one = {10, 10, 10, 11, 11, 11, 8, 8, 8};
  for (int cycle = 0; cycle < 2; ++cycle) {
    for (const double v : one)
      EXPECT_EQ(wave.step(), v);
  }
  EXPECT_EQ(wave.step(), 8.0);
  EXPECT_TRUE(wave.done());
}

TEST(WaveGenerator, StaircaseEdgesStayOnExactSamplesForHours) {
  // 0.1 s dwell at 20 kHz: 2000 samples per stair, four stairs; one hour of samples is
  // 7.2e7, so look at the stair edges around the end of that hour via restore of the count.
  WaveGenerator wave({.shape = Shape::kStaircase, .levels = {0.0, 1.0, 2.0, 3.0}, .dwell = 0.1},
                     kTs);
  std::vector<double> state(WaveGenerator::state_size());
  wave.save_state(state);
  state[2] = 72'000'000.0 - 2.0;  // two samples before the hour
  wave.restore_state(state);
  EXPECT_EQ(wave.step(), 3.0);
  EXPECT_EQ(wave.step(), 3.0);
  EXPECT_EQ(wave.step(), 0.0);  // the hour is 9000 whole periods
  EXPECT_DOUBLE_EQ(wave.cycles(), 9000.0 + 1.0 / 8000.0);
}

TEST(WaveGenerator, TableWithFixedStepIsLinearlyInterpolated) {
  // dt = 0.2 ms = 4 samples; values 0, 10, 5: the period is 2 dt = 8 samples.
  WaveGenerator wave(
      {.shape = Shape::kTable, .repeats = 1, .table_values = {0.0, 10.0, 5.0}, .table_dt = 0.2e-3},
      kTs);
  for (const double v : {0.0, 2.5, 5.0, 7.5, 10.0, 8.75, 7.5, 6.25})
    EXPECT_DOUBLE_EQ(wave.step(), v);
  EXPECT_EQ(wave.step(), 5.0);  // done: the table's last value
  EXPECT_TRUE(wave.done());
}

TEST(WaveGenerator, TableWithTimesIsLinearlyInterpolated) {
  // (0, 0), (0.1 ms, 1), (0.3 ms, -1): 6 samples per period.
  WaveGenerator wave({.shape = Shape::kTable,
                      .amplitude = 2.0,
                      .table_values = {0.0, 1.0, -1.0},
                      .table_times = {0.0, 0.1e-3, 0.3e-3}},
                     kTs);
  const std::vector<double> expected = {0.0, 1.0, 2.0, 1.0, 0.0, -1.0};
  for (int cycle = 0; cycle < 2; ++cycle) {
    for (const double v : expected)
      EXPECT_NEAR(wave.step(), v, 1e-12);
  }
}

TEST(WaveGenerator, FrequencyChangeIsPhaseContinuous) {
  WaveGenerator wave({.shape = Shape::kSine, .frequency = 100.0}, kTs);  // P = 200
  for (int k = 0; k < 150; ++k)
    wave.step();                           // position 150 / 200 = 0.75
  ASSERT_TRUE(wave.set_frequency(400.0));  // P = 50
  EXPECT_EQ(wave.period_samples(), 50.0);
  for (int m = 0; m < 100; ++m)
    EXPECT_NEAR(wave.step(), sine_at(0.75 + m / 50.0), 1e-12) << m;
  EXPECT_NEAR(wave.cycles(), 0.75 + 2.0, 1e-12);
  EXPECT_FALSE(wave.set_frequency(-1.0));
  EXPECT_FALSE(wave.set_frequency(0.0));      // a sine has no natural period
  EXPECT_FALSE(wave.set_frequency(10000.0));  // above 0.45 * sample rate
  EXPECT_EQ(wave.period_samples(), 50.0);
}

TEST(WaveGenerator, StaircaseFrequencyTimeScalesAndZeroRestoresTheNaturalPeriod) {
  WaveGenerator wave({.shape = Shape::kStaircase, .levels = {1.0, 2.0}, .dwell = 0.2e-3}, kTs);
  EXPECT_EQ(wave.period_samples(), 8.0);
  ASSERT_TRUE(wave.set_frequency(5000.0));
  EXPECT_EQ(wave.period_samples(), 4.0);
  ASSERT_TRUE(wave.set_frequency(0.0));
  EXPECT_EQ(wave.period_samples(), 8.0);
}

}  // namespace
}  // namespace selfsense::control
