// Every bad parameter is rejected at construction with a message that names it.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "selfsense/control/damping_controller.hpp"
#include "selfsense/control/filter_chain.hpp"
#include "selfsense/control/filter_design.hpp"
#include "selfsense/control/parameter_error.hpp"
#include "selfsense/control/pid.hpp"
#include "selfsense/control/setpoint_shaper.hpp"
#include "selfsense/control/wave_generator.hpp"

namespace selfsense::control {
namespace {

constexpr double kTs = 1e-4;  // 10 kHz: 0.45 * sample rate = 4500 Hz

// Runs `make`, expects a ParameterError, returns its message ("" when nothing was thrown).
std::string error_of(const std::function<void()>& make) {
  try {
    make();
  } catch (const ParameterError& e) {
    return e.what();
  }
  return {};
}

TEST(ParameterValidation, Pid) {
  const auto with = [](const std::function<void(Pid::Params&)>& edit, double ts = kTs) {
    Pid::Params p;
    p.gains = {1.0, 10.0, 0.0};
    edit(p);
    return error_of([&] { Pid(p, ts); });
  };
  EXPECT_EQ(with([](Pid::Params&) {}), "");
  EXPECT_EQ(with([](Pid::Params&) {}, 0.0), "Pid.sample_time: 0 must be > 0");
  EXPECT_EQ(with([](Pid::Params& p) { p.gains.kp = -1.0; }), "Pid.gains.kp: -1 must be >= 0");
  EXPECT_EQ(with([](Pid::Params& p) { p.gains.ki = std::nan(""); }),
            "Pid.gains.ki: nan must be finite");
  EXPECT_EQ(with([](Pid::Params& p) { p.derivative_filter_time = -1e-3; }),
            "Pid.derivative_filter_time: -0.001 must be >= 0");
  EXPECT_EQ(with([](Pid::Params& p) {
              p.gains = {0.0, 1.0, 0.1};
              p.derivative_filter_n = 10.0;
            }),
            "Pid.derivative_filter_n: needs Pid.gains.kp > 0 (Tf = kd / (kp N)); give "
            "derivative_filter_time");
  EXPECT_EQ(with([](Pid::Params& p) {
              p.output_min = 1.0;
              p.output_max = 1.0;
            }),
            "Pid.output_max: 1 must be > Pid.output_min = 1");
  EXPECT_EQ(with([](Pid::Params& p) { p.tracking_time = 5e-5; }),
            "Pid.tracking_time: 5e-05 must be 0 (off) or >= sample_time = 1e-04");
}

TEST(ParameterValidation, FilterDesigns) {
  EXPECT_EQ(error_of([] { (void)notch({.frequency = 5000.0, .quality = 2.0}, kTs); }),
            "NotchDesign.frequency: 5000 must be < 0.45 * sample rate = 4500");
  EXPECT_EQ(error_of([] { (void)notch({.frequency = 100.0}, kTs); }),
            "NotchDesign.bandwidth: 0 must be > 0");
  EXPECT_EQ(
      error_of([] { (void)notch({.frequency = 100.0, .quality = 1.0, .depth_db = -3.0}, kTs); }),
      "NotchDesign.depth_db: -3 must be >= 0");
  EXPECT_EQ(error_of([] { (void)low_pass(SecondOrderDesign{.frequency = 4500.0}, kTs); }),
            "SecondOrderDesign.frequency: 4500 must be < 0.45 * sample rate = 4500");
  EXPECT_EQ(error_of([] {
              (void)high_pass(SecondOrderDesign{100.0, 0.0}, kTs);
            }),
            "SecondOrderDesign.quality: 0 must be > 0");
  EXPECT_EQ(error_of([] { (void)low_pass(FirstOrderDesign{.frequency = -1.0}, kTs); }),
            "FirstOrderDesign.frequency: -1 must be > 0");
  EXPECT_EQ(error_of([] { (void)low_pass(FirstOrderDesign{.frequency = 10.0}, -kTs); }),
            "sample_time: -1e-04 must be > 0");
}

TEST(ParameterValidation, BiquadAndFilterChain) {
  EXPECT_EQ(error_of([] { Biquad({.b0 = 1.0, .a2 = 1.0}); }),
            "Biquad.a2: 1 must be inside (-1, 1) (unstable poles)");
  EXPECT_EQ(error_of([] { Biquad({.b0 = 1.0, .a1 = -1.6, .a2 = 0.5}); }),
            "Biquad.a1: |-1.6| must be < 1 + a2 = 1.5 (unstable poles)");
  const std::vector<BiquadCoefficients> five(5);
  EXPECT_EQ(error_of([&] { FilterChain{five}; }), "FilterChain.sections: 5 sections, at most 4");
  std::vector<BiquadCoefficients> bad(2);
  bad[1].b1 = std::numeric_limits<double>::infinity();
  EXPECT_EQ(error_of([&] { FilterChain{bad}; }),
            "FilterChain.sections[1]: Biquad.b1: inf must be finite");
}

TEST(ParameterValidation, SetpointShaper) {
  EXPECT_EQ(error_of([] { SetpointShaper({.slew_rate = -1.0}, kTs); }),
            "SetpointShaper.slew_rate: -1 must be >= 0");
  EXPECT_EQ(error_of([] { SetpointShaper({.filter = SetpointShaper::Filter::kFirstOrder}, kTs); }),
            "SetpointShaper.time_constant: 0 must be > 0");
}

TEST(ParameterValidation, WaveGenerator) {
  using Shape = WaveGenerator::Shape;
  using Config = WaveGenerator::Config;
  const auto make = [](const Config& c) { return error_of([&] { WaveGenerator(c, kTs); }); };
  EXPECT_EQ(make({.shape = Shape::kSine}), "WaveGenerator.frequency: 0 must be > 0");
  EXPECT_EQ(make({.shape = Shape::kSine, .frequency = 4600.0}),
            "WaveGenerator.frequency: 4600 must be < 0.45 * sample rate = 4500");
  EXPECT_EQ(make({.shape = Shape::kSquare, .frequency = 10.0, .phase = 1.0}),
            "WaveGenerator.phase: 1 must be < one cycle = 1");
  EXPECT_EQ(make({.shape = Shape::kTriangle, .amplitude = std::nan(""), .frequency = 10.0}),
            "WaveGenerator.amplitude: nan must be finite");
  EXPECT_EQ(make({.shape = Shape::kStaircase, .dwell = 1.0}),
            "WaveGenerator.levels: must not be empty");
  EXPECT_EQ(make({.shape = Shape::kStaircase, .levels = {1.0}}),
            "WaveGenerator.dwell: 0 must be > 0");
  EXPECT_EQ(make({.shape = Shape::kStaircase, .levels = {1.0}, .dwell = 1e-4}),
            "WaveGenerator.dwell: gives a period of 1 samples, must be >= 2");
  EXPECT_EQ(make({.shape = Shape::kTable, .table_values = {1.0}, .table_dt = 1.0}),
            "WaveGenerator.table_values: needs at least 2 values, has 1");
  EXPECT_EQ(make({.shape = Shape::kTable, .table_values = {1.0, 2.0}}),
            "WaveGenerator.table_dt: 0 must be > 0");
  EXPECT_EQ(make({.shape = Shape::kTable, .table_values = {1.0, 2.0}, .table_times = {0.0}}),
            "WaveGenerator.table_times: has 1 times for 2 table_values");
  EXPECT_EQ(make({.shape = Shape::kTable,
                  .table_values = {1.0, 2.0, 3.0},
                  .table_times = {0.0, 0.5, 0.5}}),
            "WaveGenerator.table_times[2]: 0.5 must be > WaveGenerator.table_times[1] = 0.5");
}

TEST(ParameterValidation, DampingController) {
  using Params = DampingController::Params;
  const auto make = [](const Params& p) { return error_of([&] { DampingController(p, kTs); }); };
  EXPECT_EQ(make({.frequency = 100.0}), "DampingController.gain: 0 must be > 0");
  EXPECT_EQ(make({.gain = 1.0, .frequency = 5000.0}),
            "DampingController.frequency: 5000 must be < 0.45 * sample rate = 4500");
  EXPECT_EQ(make({.gain = 1.0, .frequency = 100.0, .damping = 0.0}),
            "DampingController.damping: 0 must be > 0");
  EXPECT_EQ(make({.gain = 1.0, .frequency = 100.0, .output_limit = 0.0}),
            "DampingController.output_limit: 0 must be > 0");
  EXPECT_EQ(make({.gain = 1.0, .frequency = 100.0, .dc_block_frequency = -1.0}),
            "DampingController.dc_block_frequency: -1 must be >= 0");
  EXPECT_EQ(make({.gain = 1.0, .frequency = 100.0, .dc_block_frequency = 4500.0}),
            "DampingController.dc_block_frequency: 4500 must be < 0.45 * sample rate = 4500");
}

TEST(ParameterValidation, IsValidCollectsWithoutThrowing) {
  std::string why;
  EXPECT_FALSE((NotchDesign{.frequency = 6000.0, .quality = 1.0}.is_valid(kTs, &why)));
  EXPECT_EQ(why, "NotchDesign.frequency: 6000 must be < 0.45 * sample rate = 4500");
  EXPECT_TRUE((NotchDesign{.frequency = 60.0, .bandwidth = 10.0}.is_valid(kTs, &why)));
}

}  // namespace
}  // namespace selfsense::control
