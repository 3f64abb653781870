// save_state / restore_state round trips are bit-exact for every control law.
#include <gtest/gtest.h>

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

namespace selfsense::control {
namespace {

constexpr double kTs = 1e-4;

double input(std::size_t k) {
  const double t = static_cast<double>(k) * kTs;
  return std::sin(70.0 * t) + 0.3 * std::sin(1900.0 * t) + ((k % 37 == 0) ? 0.5 : 0.0);
}

// Steps `law` 500 samples, saves, steps 300 more, restores, steps the same 300 again: the
// outputs must be identical bit for bit. A second object of the same parameters restored from
// the saved buffer must reproduce them too.
template <typename Law, typename Step>
void expect_round_trip(Law law, Step step) {
  for (std::size_t k = 0; k < 500; ++k)
    step(law, k);
  std::vector<double> saved(law.state_size());
  law.save_state(saved);
  Law twin = law;
  std::vector<double> first;
  for (std::size_t k = 500; k < 800; ++k)
    first.push_back(step(law, k));
  law.restore_state(saved);
  twin.restore_state(saved);
  for (std::size_t k = 500; k < 800; ++k) {
    ASSERT_EQ(step(law, k), first[k - 500]) << "sample " << k;
    ASSERT_EQ(step(twin, k), first[k - 500]) << "twin, sample " << k;
  }
}

TEST(StateRoundTrip, Pid) {
  Pid::Params p;
  p.gains = {1.2, 300.0, 0.001};
  p.derivative_filter_time = 2e-4;
  p.output_min = -0.8;
  p.output_max = 0.8;
  p.tracking_time = 1e-3;
  expect_round_trip(Pid(p, kTs), [](Pid& pid, std::size_t k) {
    const double u = pid.step(0.5, input(k), 0.1);
    pid.track(0.9 * u);
    return u;
  });
  // The first sample of a fresh controller (no previous measurement) round-trips too.
  Pid fresh(p, kTs);
  std::vector<double> saved(Pid::state_size());
  fresh.save_state(saved);
  Pid other(p, kTs);
  other.step(0.0, 5.0);
  other.restore_state(saved);
  EXPECT_EQ(other.step(1.0, 2.0), fresh.step(1.0, 2.0));
}

TEST(StateRoundTrip, BiquadAndFilterChain) {
  const std::array<BiquadCoefficients, 3> sections = {
      notch({.frequency = 400.0, .quality = 3.0}, kTs),
      notch({.frequency = 1200.0, .bandwidth = 300.0, .depth_db = 20.0}, kTs),
      low_pass(SecondOrderDesign{.frequency = 2000.0}, kTs)};
  expect_round_trip(Biquad(sections[0]), [](Biquad& b, std::size_t k) { return b.step(input(k)); });
  expect_round_trip(FilterChain(sections),
                    [](FilterChain& c, std::size_t k) { return c.step(input(k)); });
}

TEST(StateRoundTrip, SetpointShaper) {
  expect_round_trip(SetpointShaper({.slew_rate = 20.0,
                                    .filter = SetpointShaper::Filter::kSecondOrder,
                                    .time_constant = 3e-3},
                                   kTs),
                    [](SetpointShaper& s, std::size_t k) { return s.step(input(k)); });
}

TEST(StateRoundTrip, WaveGeneratorEveryShape) {
  using Shape = WaveGenerator::Shape;
  const std::vector<WaveGenerator::Config> configs = {
      {.shape = Shape::kSine, .frequency = 37.0, .phase = 0.1},
      {.shape = Shape::kTriangle, .frequency = 110.0, .repeats = 3},
      {.shape = Shape::kSquare, .frequency = 90.0},
      {.shape = Shape::kStaircase, .levels = {0.0, 0.5, 1.0}, .dwell = 7e-3},
      {.shape = Shape::kTable, .table_values = {0.0, 1.0, 0.2}, .table_times = {0.0, 0.01, 0.013}}};
  for (const WaveGenerator::Config& config : configs) {
    expect_round_trip(WaveGenerator(config, kTs), [](WaveGenerator& w, std::size_t k) {
      if (k == 650) w.set_frequency(w.config().shape == Shape::kSine ? 52.0 : 0.0);
      return w.step();
    });
  }
}

TEST(StateRoundTrip, DampingController) {
  using Law = DampingController::Law;
  expect_round_trip(
      DampingController(
          {.gain = 0.4, .frequency = 300.0, .damping = 0.3, .dc_block_frequency = 15.0}, kTs),
      [](DampingController& d, std::size_t k) { return d.step(input(k)); });
  expect_round_trip(
      DampingController({.law = Law::kVelocity, .gain = 1e-4, .frequency = 2000.0}, kTs),
      [](DampingController& d, std::size_t k) { return d.step(input(k)); });
}

}  // namespace
}  // namespace selfsense::control
