// identify() hands the two sides' fits to the caller's runner (transducer_fit.hpp): run on two
// threads by the runner `selfsense identify` uses (evaluation::run_on_threads) they give the model
// that one after the other gives, to the last bit; the runner waits for every piece and rethrows.
#include "selfsense/evaluation/work_runner.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <optional>
#include <span>
#include <stdexcept>
#include <thread>
#include <vector>

#include "selfsense/identification/transducer_fit.hpp"

namespace selfsense::evaluation {
namespace {

using identification::defaults_for;
using identification::IdentificationOptions;
using identification::identify;
using identification::TransducerSignals;
using identification::WorkRunner;

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
    run_on_threads(work);
  };
  const models::TransducerModel one_after_the_other =
      identify(signals, models::Structure::kHysteresisCreep, o);
  const models::TransducerModel parallel =
      identify(signals, models::Structure::kHysteresisCreep, o, on_threads);
  EXPECT_EQ(pieces, 2U);
  expect_same_side(parallel.sensor, one_after_the_other.sensor);
  expect_same_side(parallel.actuator, one_after_the_other.actuator);
}

TEST(WorkRunner, RunsEveryPieceOnAThreadBesideTheCallersAndRethrowsAfterAll) {
  const std::thread::id caller = std::this_thread::get_id();
  std::vector<std::thread::id> where(3);
  bool last_ran = false;
  const std::vector<std::function<void()>> work{[&] { where[0] = std::this_thread::get_id(); },
                                                [&] {
                                                  where[1] = std::this_thread::get_id();
                                                  throw std::runtime_error("second");
                                                },
                                                [&] {
                                                  where[2] = std::this_thread::get_id();
                                                  last_ran = true;
                                                }};
  EXPECT_THROW(run_on_threads(work), std::runtime_error);
  EXPECT_TRUE(last_ran);
  EXPECT_EQ(where[0], caller);
  EXPECT_NE(where[1], caller);
  EXPECT_NE(where[2], caller);
  run_on_threads({});  // nothing to run
}

}  // namespace
}  // namespace selfsense::evaluation
