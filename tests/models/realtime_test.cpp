// Real-time path proof for the model layer: reconstruction and forward steps never allocate.
#include <gtest/gtest.h>

#include <cmath>
#include <utility>
#include <vector>

#include "selfsense/identification/stress_hysteresis_fit.hpp"
#include "selfsense/models/reconstructor.hpp"
#include "selfsense/models/stress_hysteresis.hpp"
#include "support/allocation_counter.hpp"
#include "support/transducer_data.hpp"

namespace selfsense::models {
namespace {

using identification::fit_stress_hysteresis;

static_assert(noexcept(std::declval<Reconstructor&>().step(0.0, 0.0)));
static_assert(noexcept(std::declval<ForwardModel&>().step(0.0, 0.0)));
static_assert(noexcept(std::declval<StressHysteresisReconstructor&>().step(0.0, 0.0)));
static_assert(noexcept(std::declval<StressHysteresisForward&>().step(0.0, 0.0)));

TEST(ModelRealTime, StepsAndStateSavesDoNotAllocate) {
  const TransducerModel model = test::typical_transducer(1e-4);
  const test::TransducerData d = test::transducer_data(model, 3000, 1e-4, 5);
  Reconstructor r(model);
  ForwardModel f(model);
  std::vector<double> state(r.state_size());
  double sink = 0.0;
  test::AllocationCounter counter;
  for (std::size_t k = 0; k < d.e.size(); ++k) {
    const Reconstructor::Estimate est = r.step(d.e[k], d.d[k]);
    const ForwardModel::Output out = f.step(d.e[k], est.stress);
    r.save_state(state);
    r.restore_state(state);
    sink += est.strain + out.sensed;
  }
  EXPECT_EQ(counter.count(), 0U);
  EXPECT_TRUE(std::isfinite(sink));
}

TEST(ModelRealTime, NumericalStressReconstructionDoesNotAllocate) {
  const test::TransducerData d =
      test::transducer_data(test::typical_transducer(1e-4), 3000, 1e-4, 6);
  StressHysteresisReconstructor r(fit_stress_hysteresis(d.e, d.t, d.d, d.s, 1e-4, 12));
  double sink = 0.0;
  test::AllocationCounter counter;
  for (std::size_t k = 0; k < d.e.size(); ++k)
    sink += r.step(d.e[k], d.d[k]).stress;
  EXPECT_EQ(counter.count(), 0U);
  EXPECT_TRUE(std::isfinite(sink));
}

// The stress-dependent model in both directions, with its state saved and restored every
// sample as a flight recorder or a hot swap would: no allocation (C or C++), no free, no lock.
TEST(ModelRealTime, StressDependentStepsAndStateSavesDoNotAllocateOrLock) {
  const test::TransducerData d =
      test::transducer_data(test::typical_transducer(1e-4), 3000, 1e-4, 7);
  const StressHysteresisModel model = fit_stress_hysteresis(d.e, d.t, d.d, d.s, 1e-4, 12);
  StressHysteresisReconstructor r(model);
  StressHysteresisForward f(model);
  std::vector<double> r_state(r.state_size());
  std::vector<double> f_state(f.state_size());
  double sink = 0.0;
  test::AllocationCounter counter;
  for (std::size_t k = 0; k < d.e.size(); ++k) {
    const StressHysteresisReconstructor::Estimate est = r.step(d.e[k], d.d[k]);
    const StressHysteresisForward::Output out = f.step(d.e[k], est.stress);
    r.save_state(r_state);
    r.restore_state(r_state);
    f.save_state(f_state);
    f.restore_state(f_state);
    sink += est.strain + out.sensed;
  }
  EXPECT_EQ(counter.count(), 0U);
  EXPECT_EQ(counter.deallocations(), 0U);
  EXPECT_EQ(counter.locks(), 0U);
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
}  // namespace selfsense::models
