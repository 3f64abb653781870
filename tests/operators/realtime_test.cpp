// Real-time path proof: every per-sample method is noexcept and allocates nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <utility>
#include <vector>

#include "selfsense/operators/hysteresis_creep.hpp"
#include "selfsense/operators/modified_prandtl_ishlinskii.hpp"
#include "selfsense/operators/play.hpp"
#include "selfsense/operators/threshold_creep.hpp"
#include "selfsense/operators/typical_stack.hpp"
#include "support/allocation_counter.hpp"
#include "support/random_walk.hpp"

namespace selfsense::operators {
namespace {

static_assert(noexcept(std::declval<PlayOperator&>().step(0.0)));
static_assert(noexcept(std::declval<StopOperator&>().step(0.0)));
static_assert(noexcept(std::declval<PrandtlIshlinskii&>().step(0.0)));
static_assert(noexcept(std::declval<PrandtlIshlinskii&>().set_state({})));
static_assert(noexcept(std::declval<ModifiedPrandtlIshlinskii&>().step(0.0)));
static_assert(noexcept(std::declval<ModifiedPrandtlIshlinskiiInverse&>().step(0.0)));
static_assert(noexcept(std::declval<LinearCreep&>().step(0.0)));
static_assert(noexcept(std::declval<ThresholdCreep&>().step(0.0)));
static_assert(noexcept(std::declval<NonlinearCreep&>().step(0.0)));
static_assert(noexcept(std::declval<HysteresisCreep&>().step(0.0)));
static_assert(noexcept(std::declval<HysteresisCreep&>().inverse_step(0.0)));
static_assert(noexcept(std::declval<HysteresisCreep&>().set_state({})));
static_assert(noexcept(std::declval<HysteresisCreepCompensator&>().step(0.0)));

TEST(RealTime, PerSampleStepsDoNotAllocate) {
  TypicalStackSize size;
  size.plays = 32;
  size.dead_zones = 16;
  size.eigenvalues = 10;
  size.creep_plays = 4;
  HysteresisCreep sensor(typical_stack_charge(size), 1e-4);
  HysteresisCreep actuator(typical_stack_strain(size), 1e-4);
  HysteresisCreepCompensator feedforward(HysteresisCreep(typical_stack_strain(size), 1e-4), 0.0,
                                         2e6);
  PrandtlIshlinskii pi(sensor.params().hysteresis);
  ModifiedPrandtlIshlinskii mpi(PrandtlIshlinskii(sensor.params().hysteresis),
                                DeadZoneSuperposition(sensor.params().superposition));
  ModifiedPrandtlIshlinskiiInverse mpi_inv = mpi.inverse();
  ThresholdCreep creep(sensor.params().creep, 1e-4);
  NonlinearCreep eq28(PrandtlIshlinskii(sensor.params().hysteresis),
                      LinearCreep({{10.0, 1.0}, {0.1, 0.1}}, 1e-4));
  // With hinges on every play (the preisach-creep structure): the hinge table and the
  // inverse's Newton solve.
  HysteresisCreep::Params hinged = typical_stack_strain(size);
  for (const double r : hinged.hysteresis.thresholds) {
    for (const double level : {0.5e6, 1.0e6, 1.5e6}) {
      hinged.hinges.thresholds.push_back(r);
      hinged.hinges.levels.push_back(level);
      hinged.hinges.weights.push_back(0.02 * hinged.hysteresis.linear_weight);
    }
  }
  HysteresisCreep hinged_model(hinged, 1e-4);
  HysteresisCreepCompensator hinged_feedforward(HysteresisCreep(hinged, 1e-4), 0.0, 2e6);
  PlayOperator play(0.5);
  StopOperator stop(0.5);
  const std::vector<double> e = test::random_walk(5000, 0.0, 2e6, 2e4, 1);
  std::vector<double> saved(sensor.state().begin(), sensor.state().end());

  double sink = 0.0;
  test::AllocationCounter counter;
  for (const double v : e) {
    sink += sensor.step(v) + actuator.step(v) + feedforward.step(1e-6 * v * 0.5e-3);
    sink += pi.step(v) + mpi_inv.step(mpi.step(v)) + creep.step(v) + eq28.step(v);
    sink += play.step(v) + stop.step(v) + sensor.inverse_step(0.05);
    sink += hinged_model.step(v) + hinged_feedforward.step(1e-6 * v * 0.5e-3);
    sensor.set_state(saved);
  }
  EXPECT_EQ(counter.count(), 0U);
  EXPECT_TRUE(std::isfinite(sink));
}

TEST(RealTime, CounterSeesAllocations) {
  // The instrument works: an allocation while armed is counted.
  test::AllocationCounter counter;
  auto* p = new std::vector<double>(10);
  delete p;
  EXPECT_GE(counter.count(), 1U);
}

}  // namespace
}  // namespace selfsense::operators
