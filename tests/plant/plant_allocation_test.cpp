// Plant::step() never allocates: global operator new is replaced by a counting version.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "plant_test_util.hpp"
#include "selfsense/plant/plant_yaml.hpp"

namespace {
std::atomic<long> g_allocations{0};
}  // namespace

void* operator new(std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc{};
}
void* operator new[](std::size_t size) {
  return ::operator new(size);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t /*size*/) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t /*size*/) noexcept {
  std::free(p);
}

namespace selfsense::plant {
namespace {

TEST(PlantAllocation, StepSaveRestoreAndFaultsDoNotAllocate) {
  PlantFile file = load_plant_file(test::config_dir() / "all_effects.yaml");
  Plant plant{file.plant};
  const long before = g_allocations.load();
  double sink = 0.0;
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
  EXPECT_EQ(g_allocations.load() - before, 0);
  EXPECT_TRUE(std::isfinite(sink));
  EXPECT_GT(g_allocations.load(), 0);  // the counter works: construction allocated
}

}  // namespace
}  // namespace selfsense::plant
