// Real-time path proof for the runtime model type: every structure's step (accepted and
// rejected samples), state save and restore, and the hot-swap carry-over never allocate.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "selfsense/identification/stress_hysteresis_fit.hpp"
#include "selfsense/models/runtime_model.hpp"
#include "support/allocation_counter.hpp"
#include "support/transducer_data.hpp"

namespace selfsense::models {
namespace {

static_assert(noexcept(std::declval<Reconstruction&>().step(0.0, 0.0)));
static_assert(noexcept(std::declval<Simulation&>().step(0.0, 0.0)));
static_assert(
    noexcept(std::declval<Reconstruction&>().adopt_state(std::declval<const Reconstruction&>())));
static_assert(noexcept(std::declval<Reconstruction&>().save_state(std::declval<SavedState&>())));
static_assert(
    noexcept(std::declval<Reconstruction&>().restore_state(std::declval<const SavedState&>())));

std::vector<TransducerModel> every_runtime_structure(const test::TransducerData& d, double ts) {
  TransducerModel affine = test::typical_transducer(ts);
  affine.drive_range = InputRange{0.0, 2e6};
  affine.sensed_range = InputRange{-0.05, 0.1};
  TransducerModel vectorial;
  vectorial.structure = Structure::kStressHysteresis;
  vectorial.sample_time = ts;
  vectorial.vectorial = identification::fit_stress_hysteresis(d.e, d.t, d.d, d.s, ts, 12);
  vectorial.drive_range = affine.drive_range;
  // The stress structure on one channel, the plain side on the other (stress_sides.hpp).
  TransducerModel stressed_sensor = vectorial;
  stressed_sensor.vectorial->actuator.reset();
  stressed_sensor.actuator = affine.actuator;
  TransducerModel stressed_actuator = vectorial;
  stressed_actuator.vectorial->sensor.reset();
  stressed_actuator.sensor = affine.sensor;
  return {affine, vectorial, stressed_sensor, stressed_actuator};
}

TEST(RuntimeModelRealTime, StepsStatesAndSwapsDoNotAllocate) {
  constexpr double kTs = 1e-4;
  const test::TransducerData d =
      test::transducer_data(test::typical_transducer(kTs), 4000, 1e-4, 5);
  for (const TransducerModel& model : every_runtime_structure(d, kTs)) {
    Reconstruction r(model, RuntimeOptions{5e-5});
    Reconstruction next(model, RuntimeOptions{5e-5});
    Simulation f(model);
    SavedState state = r.make_saved_state();
    SavedState forward_state = f.make_saved_state();
    double sink = 0.0;
    test::AllocationCounter counter;
    for (std::size_t k = 0; k < d.e.size(); ++k) {
      // Every 97th sample is bad: the rejection path runs too.
      const double e = k % 97 == 0 ? std::numeric_limits<double>::quiet_NaN() : d.e[k];
      const Reconstruction::Estimate est = r.step(e, d.d[k]);
      const Simulation::Output out = f.step(d.e[k], est.stress);
      sink += static_cast<double>(r.save_state(state)) + out.strain;
      sink += static_cast<double>(r.restore_state(state));
      sink += static_cast<double>(f.save_state(forward_state));
      sink += static_cast<double>(f.restore_state(forward_state));
      if (k % 500 == 0) next.adopt_state(r);
    }
    EXPECT_EQ(counter.count(), 0U) << to_string(model.structure);
    EXPECT_TRUE(std::isfinite(sink));
    EXPECT_GT(r.counts()[SampleStatus::kInputNotFinite], 0U);
  }
}

}  // namespace
}  // namespace selfsense::models
