// Plant::step() never allocates (tests/support/allocation_counter.cpp counts operator new).
#include <gtest/gtest.h>

#include <cmath>

#include "plant_test_util.hpp"
#include "selfsense/plant_io/plant_yaml.hpp"
#include "support/allocation_counter.hpp"

namespace selfsense::plant {
namespace {

TEST(PlantAllocation, StepSaveRestoreAndFaultsDoNotAllocate) {
  PlantFile file = load_plant_file(test::config_dir() / "all_effects.yaml");
  file.plant.heating.enabled = true;  // the self-heating's step too
  Plant plant{file.plant};
  double sink = 0.0;
  selfsense::test::AllocationCounter counter;
  for (int k = 0; k < 20000; ++k) {
    const double e = 1.0e6 * (1.0 + std::sin(0.01 * k));
    sink += plant.step(StepInput{e, 100.0 * std::cos(0.003 * k), 25.0 + k * 1e-3}).d_meas_c_per_m2;
    if (k == 5000) {
      plant.inject(FaultKind::stuck_adc, Channel::both, k + 10, 100);
      plant.inject(FaultKind::amplifier_fault, Channel::both, k + 500, 100);
    }
  }
  const Plant::State saved = plant.save();
  plant.restore(saved);
  EXPECT_EQ(counter.count(), 0U);
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
}  // namespace selfsense::plant
