// The shipped model's per-sample cost against the model it refines, timed in the same process.
//
// Workload per sample, as operator_bench's reconstruction workload: the sensor-side operator
// (E -> D), the actuator-side operator (E -> S) and the feedforward compensator (desired S ->
// E, the inverse solved per sample), built from config/models/sim.yaml (preisach-creep, 7
// hinges on 23 plays per side). The reference is the same model with its hinges removed (its
// hysteresis-creep part: plays, creep, dead zones; the inverse in closed form).
//
// Statistic: blocks of kBlock samples timed alternately on both, the ratio of each pair, the
// median of kPairs ratios. A core taken away for a while slows one block of one pair; the
// median does not see it. Bound: the ratio measured after the hinge table (docs/benchmarks.md,
// "Speed kept by tests") x 1.5.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <string>
#include <vector>

#include "selfsense/model_io/model_yaml.hpp"
#include "selfsense/operators/hysteresis_creep.hpp"
#include "support/random_walk.hpp"

namespace selfsense {
namespace {

using operators::HysteresisCreep;
using operators::HysteresisCreepCompensator;

constexpr std::size_t kBlock = 2048;
constexpr std::size_t kPairs = 101;
// Median ratio measured 2026-11-26 after the hinge segments (1.73-2.01 in 11 runs, load average
// 1-6; 6.8-7.3 before them), x 1.5 (see the header).
constexpr double kMeasuredRatio = 2.0;
constexpr double kBound = 1.5 * kMeasuredRatio;

struct Workload {
  HysteresisCreep sensor;
  HysteresisCreep actuator;
  HysteresisCreepCompensator feedforward;

  Workload(const HysteresisCreep::Params& d, const HysteresisCreep::Params& s, double ts,
           double drive_max)
      : sensor(d, ts), actuator(s, ts), feedforward(HysteresisCreep(s, ts), 0.0, drive_max) {}

  double step(double e, double desired) {
    return sensor.step(e) + actuator.step(e) + feedforward.step(desired);
  }
};

double seconds_for(Workload& w, const std::vector<double>& e, const std::vector<double>& desired,
                   std::size_t from, double* sink) {
  const auto t0 = std::chrono::steady_clock::now();
  double sum = 0.0;
  for (std::size_t k = from; k < from + kBlock; ++k)
    sum += w.step(e[k], desired[k]);
  const auto t1 = std::chrono::steady_clock::now();
  *sink += sum;
  return std::chrono::duration<double>(t1 - t0).count();
}

TEST(ModelCost, ShippedModelAgainstTheModelWithoutHinges) {
  const models::TransducerModel model =
      models::load_model(SELFSENSE_SOURCE_DIR "/config/models/sim.yaml");
  ASSERT_TRUE(model.sensor && model.actuator && model.drive_range);
  const double ts = model.sample_time;
  const double drive_max = model.drive_range->max;
  HysteresisCreep::Params d = model.sensor->op;
  HysteresisCreep::Params s = model.actuator->op;
  ASSERT_GT(d.hinges.thresholds.size(), 100U) << "the shipped model has lost its hinges";
  HysteresisCreep::Params d_plain = d;
  HysteresisCreep::Params s_plain = s;
  d_plain.hinges = {};
  s_plain.hinges = {};

  // A field walk over the drive range, and a desired strain the actuator side reaches.
  const std::size_t n = kBlock * 8;
  const std::vector<double> e = test::random_walk(n, 0.0, drive_max, 0.01 * drive_max, 5);
  const std::vector<double> e_desired = test::random_walk(n, 0.0, drive_max, 0.01 * drive_max, 6);
  std::vector<double> desired(n);
  HysteresisCreep twin(s, ts);
  for (std::size_t k = 0; k < n; ++k)
    desired[k] = twin.step(e_desired[k]);

  Workload shipped(d, s, ts, drive_max);
  Workload plain(d_plain, s_plain, ts, drive_max);
  double sink = 0.0;
  // Warm the caches and branch predictors on both.
  for (std::size_t from = 0; from < n; from += kBlock) {
    seconds_for(shipped, e, desired, from, &sink);
    seconds_for(plain, e, desired, from, &sink);
  }
  std::vector<double> ratios;
  std::vector<double> shipped_ns;
  std::vector<double> plain_ns;
  for (std::size_t pair = 0; pair < kPairs; ++pair) {
    const std::size_t from = (pair % 8) * kBlock;
    // Alternate which goes first, so that neither always follows the other's cache footprint.
    double a = 0.0;
    double b = 0.0;
    if (pair % 2 == 0) {
      a = seconds_for(shipped, e, desired, from, &sink);
      b = seconds_for(plain, e, desired, from, &sink);
    } else {
      b = seconds_for(plain, e, desired, from, &sink);
      a = seconds_for(shipped, e, desired, from, &sink);
    }
    ratios.push_back(a / b);
    shipped_ns.push_back(1e9 * a / static_cast<double>(kBlock));
    plain_ns.push_back(1e9 * b / static_cast<double>(kBlock));
  }
  const auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  const double ratio = median(ratios);
  std::printf(
      "per sample (median of %zu blocks of %zu): shipped %.0f ns, without hinges %.0f ns; "
      "median ratio %.2f (bound %.2f)\n",
      kPairs, kBlock, median(shipped_ns), median(plain_ns), ratio, kBound);
  RecordProperty("median_ratio", std::to_string(ratio));
  EXPECT_TRUE(std::isfinite(sink));
  EXPECT_LE(ratio, kBound);
}

}  // namespace
}  // namespace selfsense
