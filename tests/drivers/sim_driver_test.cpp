// The simulated transducer as a driver: the plant runs several samples per loop cycle, and a
// fault flag raised in any of them reaches the loop, not only one in the sample read last.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "selfsense/drivers/sim/simulated_transducer.hpp"
#include "selfsense/plant/config.hpp"
#include "selfsense/plant/status.hpp"

namespace selfsense::drivers {
namespace {

constexpr double kPlantRateHz = 40000.0;
constexpr double kLoopRateHz = 10000.0;  // four plant samples per cycle

TEST(SimulatedTransducer, AFaultInAnyPlantSampleOfTheCycleIsReported) {
  plant::PlantConfig config;
  config.sample_rate_hz = kPlantRateHz;
  // One NaN sample on D, in the middle of the second cycle's four plant samples.
  config.faults.push_back(
      plant::FaultEntry{plant::FaultKind::nan_sample, plant::Channel::d, 5.0 / kPlantRateHz, 0.0});
  SimulatedTransducer driver(config);
  std::string why;
  ASSERT_TRUE(driver.configure(runtime::DriverSetup{1.0 / kLoopRateHz}, &why)) << why;
  ASSERT_EQ(driver.substeps(), 4);
  ASSERT_TRUE(driver.activate(&why)) << why;
  runtime::InputSample sample{};
  EXPECT_EQ(driver.read(sample), runtime::DriverStatus::kOk);
  EXPECT_EQ(driver.read(sample), runtime::DriverStatus::kBadData);
  EXPECT_EQ(driver.read(sample), runtime::DriverStatus::kOk);
  EXPECT_EQ(driver.counters().bad_data, 1U);
  // The cause, by name, among the driver's events (status counters.driver_events).
  const runtime::DriverCounters c = driver.counters();
  std::uint64_t nan_cycles = 0;
  std::uint64_t others = 0;
  for (const runtime::NamedCount& e : c.event_list()) {
    (std::string(e.name) == "nan_sample_cycles" ? nan_cycles : others) += e.value;
  }
  EXPECT_EQ(c.event_list().size(), 6U);
  EXPECT_EQ(nan_cycles, 1U);
  EXPECT_EQ(others, 0U);
}

// A late sample used to pass as kOk (the plant flagged it, the driver mapped nothing): found by
// the soak test (tests/soak), which injects every plant fault kind into the running daemon.
TEST(SimulatedTransducer, ASampleLateByALoopPeriodIsATimeoutAndOneLateByLessIsNot) {
  plant::PlantConfig config;
  config.sample_rate_hz = kPlantRateHz;
  const double period = 1.0 / kLoopRateHz;
  // Cycle 2 (plant samples 4..7): late by half a period; cycle 4 (12..15): by a whole one.
  config.faults.push_back(plant::FaultEntry{plant::FaultKind::late_sample, plant::Channel::both,
                                            5.0 / kPlantRateHz, 0.0, 0.5 * period});
  config.faults.push_back(plant::FaultEntry{plant::FaultKind::late_sample, plant::Channel::both,
                                            13.0 / kPlantRateHz, 0.0, period});
  SimulatedTransducer driver(config);
  std::string why;
  ASSERT_TRUE(driver.configure(runtime::DriverSetup{period}, &why)) << why;
  ASSERT_TRUE(driver.activate(&why)) << why;
  runtime::InputSample sample{};
  EXPECT_EQ(driver.read(sample), runtime::DriverStatus::kOk);
  EXPECT_EQ(driver.read(sample), runtime::DriverStatus::kOk);
  EXPECT_NE(sample.device_status & plant::kLateSample, 0U);
  EXPECT_EQ(driver.read(sample), runtime::DriverStatus::kOk);
  EXPECT_EQ(driver.read(sample), runtime::DriverStatus::kTimeout);
  EXPECT_EQ(driver.read(sample), runtime::DriverStatus::kOk);
  EXPECT_EQ(driver.counters().timeouts, 1U);
}

// The bench's force input (ctl impulse): a pulse of the force asked for, from the next cycle on,
// for the cycles its duration lasts, on top of the constant load; the stack's stress shows it
// in those cycles and only from them on (a twin without the pulse gives the same samples before).
TEST(SimulatedTransducer, AForcePulseActsFromTheNextCycleForItsDuration) {
  plant::PlantConfig config;
  config.sample_rate_hz = kPlantRateHz;
  config.mechanics.enabled = true;
  config.mechanics.load_stiffness_n_per_m = 15e6;
  SimulatedTransducer pushed(config);
  SimulatedTransducer twin(config);
  std::string why;
  for (SimulatedTransducer* d : {&pushed, &twin}) {
    ASSERT_TRUE(d->configure(runtime::DriverSetup{1.0 / kLoopRateHz}, &why)) << why;
    ASSERT_TRUE(d->activate(&why)) << why;
  }
  runtime::ForceInput* input = pushed.force_input();
  ASSERT_NE(input, nullptr);
  runtime::InputSample a{};
  runtime::InputSample b{};
  for (int k = 0; k < 20; ++k) {
    ASSERT_EQ(pushed.read(a), runtime::DriverStatus::kOk);
    ASSERT_EQ(twin.read(b), runtime::DriverStatus::kOk);
    EXPECT_EQ(a.t_ref, b.t_ref) << k;
  }
  input->apply(-500.0, 3.0 / kLoopRateHz);  // three cycles
  double pushed_apart = 0.0;
  for (int k = 0; k < 3; ++k) {
    ASSERT_EQ(pushed.read(a), runtime::DriverStatus::kOk);
    ASSERT_EQ(twin.read(b), runtime::DriverStatus::kOk);
    pushed_apart = std::max(pushed_apart, std::abs(a.t_ref - b.t_ref));
  }
  // 500 N on the stack's 10 mm x 10 mm face is 5 MPa: the dynamic stress follows a good part.
  EXPECT_GT(pushed_apart, 1e5);
  // After the pulse the two ring apart, then the difference decays (no force left).
  double last = 0.0;
  for (int k = 0; k < 2000; ++k) {
    ASSERT_EQ(pushed.read(a), runtime::DriverStatus::kOk);
    ASSERT_EQ(twin.read(b), runtime::DriverStatus::kOk);
    last = std::abs(a.t_ref - b.t_ref);
  }
  EXPECT_LT(last, 0.01 * pushed_apart);
}

}  // namespace
}  // namespace selfsense::drivers
