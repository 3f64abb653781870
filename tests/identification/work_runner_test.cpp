// identify() hands the two sides' fits to the caller's runner (transducer_fit.hpp): run on two
// threads they give the model that one after the other gives, to the last bit.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <future>
#include <numbers>
#include <optional>
#include <span>
#include <vector>

#include "selfsense/identification/transducer_fit.hpp"

namespace selfsense::identification {
namespace {

void expect_same_side(const std::optional<models::SideModel>& a,
                      const std::optional<models::SideModel>& b) {
  ASSERT_EQ(a.has_value(), b.has_value());
  if (!a) return;
  EXPECT_EQ(a->history, b->history);
  EXPECT_EQ(a->linear_gains, b->linear_gains);
  EXPECT_EQ(a->offset, b->offset);
  EXPECT_EQ(a->op.hysteresis.linear_weight, b->op.hysteresis.linear_weight);
  EXPECT_EQ(a->op.hysteresis.weights, b->op.hysteresis.weights);
  EXPECT_EQ(a->op.creep.weights, b->op.creep.weights);
  EXPECT_EQ(a->op.hinges.weights, b->op.hinges.weights);
  EXPECT_EQ(a->op.superposition.upper_weights, b->op.superposition.upper_weights);
  EXPECT_EQ(a->op.superposition.lower_weights, b->op.superposition.lower_weights);
}

TEST(WorkRunner, SidesOnTwoThreadsGiveTheModelOfOneAfterTheOther) {
  constexpr std::size_t kSamples = 6000;
  std::vector<double> e;
  std::vector<double> d;
  std::vector<double> s;
  for (std::size_t k = 0; k < kSamples; ++k) {
    const double time = static_cast<double>(k) * 1e-3;
    const double x = 1e6 * std::sin(2 * std::numbers::pi * time) * (1.0 - 0.1 * time);
    e.push_back(x);
    d.push_back(1e-8 * x + 2e-15 * x * std::abs(x));
    s.push_back(4e-10 * x + 1e-16 * x * x);
  }
  IdentificationOptions o = defaults_for(models::Structure::kHysteresisCreep);
  o.plays = 6;
  o.dead_zones = 2;
  const TransducerSignals signals{e, d, {}, s, 1e-3};
  std::size_t pieces = 0;
  const WorkRunner on_threads = [&pieces](std::span<const std::function<void()>> work) {
    pieces = work.size();
    std::vector<std::future<void>> started;
    for (const auto& piece : work)
      started.push_back(std::async(std::launch::async, piece));
    for (auto& f : started)
      f.get();
  };
  const models::TransducerModel one_after_the_other =
      identify(signals, models::Structure::kHysteresisCreep, o);
  const models::TransducerModel parallel =
      identify(signals, models::Structure::kHysteresisCreep, o, on_threads);
  EXPECT_EQ(pieces, 2U);
  expect_same_side(parallel.sensor, one_after_the_other.sensor);
  expect_same_side(parallel.actuator, one_after_the_other.actuator);
}

}  // namespace
}  // namespace selfsense::identification
