// The simulated transducer as a driver: the plant runs several samples per loop cycle, and a
// fault flag raised in any of them reaches the loop, not only one in the sample read last.
#include <gtest/gtest.h>

#include <string>

#include "selfsense/plant/config.hpp"
#include "sim/simulated_transducer.hpp"

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

}  // namespace
}  // namespace selfsense::drivers
