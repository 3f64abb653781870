// Real-time path proof: every per-sample method of the control laws is noexcept and allocates
// nothing.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <utility>
#include <vector>

#include "selfsense/control/damping_controller.hpp"
#include "selfsense/control/filter_chain.hpp"
#include "selfsense/control/filter_design.hpp"
#include "selfsense/control/pid.hpp"
#include "selfsense/control/setpoint_shaper.hpp"
#include "selfsense/control/wave_generator.hpp"
#include "support/allocation_counter.hpp"

namespace selfsense::control {
namespace {

static_assert(noexcept(std::declval<Pid&>().step(0.0, 0.0, 0.0)));
static_assert(noexcept(std::declval<Pid&>().track(0.0)));
static_assert(noexcept(std::declval<Pid&>().set_gains({})));
static_assert(noexcept(std::declval<Pid&>().reset_bumpless(0.0, 0.0)));
static_assert(noexcept(std::declval<Biquad&>().step(0.0)));
static_assert(noexcept(std::declval<Biquad&>().set_coefficients({})));
static_assert(noexcept(std::declval<FilterChain&>().step(0.0)));
static_assert(noexcept(std::declval<FilterChain&>().set_section(0, {})));
static_assert(noexcept(std::declval<SetpointShaper&>().step(0.0)));
static_assert(noexcept(std::declval<WaveGenerator&>().step()));
static_assert(noexcept(std::declval<WaveGenerator&>().set_frequency(1.0)));
static_assert(noexcept(std::declval<DampingController&>().step(0.0)));

constexpr double kTs = 5e-5;  // 20 kHz

TEST(RealTime, StepsOfEveryControlLawDoNotAllocate) {
  Pid::Params pid_params;
  pid_params.gains = {1.0, 200.0, 1e-4};
  pid_params.derivative_filter_n = 10.0;
  pid_params.output_min = -1.0;
  pid_params.output_max = 1.0;
  pid_params.tracking_time = 1e-3;
  Pid pid(pid_params, kTs);
  const std::array<BiquadCoefficients, 3> sections = {
      notch({.frequency = 700.0, .quality = 5.0}, kTs),
      notch({.frequency = 2100.0, .quality = 5.0}, kTs),
      low_pass(SecondOrderDesign{.frequency = 4000.0}, kTs)};
  FilterChain chain(sections);
  const BiquadCoefficients replacement = notch({.frequency = 800.0, .quality = 4.0}, kTs);
  SetpointShaper shaper(
      {.slew_rate = 1.0, .filter = SetpointShaper::Filter::kSecondOrder, .time_constant = 1e-3},
      kTs);
  using Shape = WaveGenerator::Shape;
  std::vector<WaveGenerator> waves = {
      WaveGenerator({.shape = Shape::kSine, .frequency = 10.0}, kTs),
      WaveGenerator({.shape = Shape::kTriangle, .frequency = 10.0, .repeats = 3}, kTs),
      WaveGenerator({.shape = Shape::kSquare, .frequency = 10.0}, kTs),
      WaveGenerator({.shape = Shape::kStaircase, .levels = {0.0, 1.0, 2.0}, .dwell = 0.01}, kTs),
      WaveGenerator({.shape = Shape::kTable,
                     .table_values = {0.0, 1.0, 0.5, 0.0},
                     .table_times = {0.0, 0.01, 0.02, 0.05}},
                    kTs)};
  DampingController ppf(
      {.gain = 0.5, .frequency = 500.0, .damping = 0.3, .dc_block_frequency = 20.0}, kTs);
  DampingController velocity(
      {.law = DampingController::Law::kVelocity, .gain = 1e-4, .frequency = 5000.0}, kTs);
  std::array<double, 16> state{};

  double sink = 0.0;
  double y = 0.0;
  test::AllocationCounter counter;
  for (int k = 0; k < 100000; ++k) {
    double r = 0.0;
    for (WaveGenerator& w : waves)
      r += w.step();
    r = shaper.step(r);
    const double u = pid.step(r, y, 0.01);
    pid.track(0.9 * u);
    const double filtered = chain.step(u);
    y += 0.05 * (filtered - y);
    sink += ppf.step(y) + velocity.step(y);
    if (k % 1000 == 0) {
      sink += pid.set_gains({1.0 + 1e-6 * k, 200.0, 1e-4}) ? 1.0 : 0.0;
      sink += chain.set_section(0, replacement) ? 1.0 : 0.0;
      sink += waves[0].set_frequency(10.0 + 1e-4 * k) ? 1.0 : 0.0;
      pid.save_state(state);
      pid.restore_state(state);
      chain.save_state(state);
      chain.restore_state(state);
      waves[1].save_state(state);
      waves[1].restore_state(state);
      shaper.save_state(state);
      shaper.restore_state(state);
      ppf.save_state(state);
      ppf.restore_state(state);
    }
    if (k == 50000) {
      pid.reset_bumpless(y, u);
      shaper.reset(y);
      chain.reset(u);
      ppf.reset(y);
      waves[1].restart();
    }
  }
  EXPECT_EQ(counter.count(), 0U);
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
}  // namespace selfsense::control
