// A stress-hysteresis model completed by a plain side (models/stress_sides.hpp): each channel
// runs on its own part, reconstruction inverts the forward model with either part as the
// sensor, and the state and the hot swap carry both parts.
#include "selfsense/models/stress_sides.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "selfsense/identification/stress_hysteresis_fit.hpp"
#include "selfsense/models/runtime_model.hpp"
#include "support/transducer_data.hpp"

namespace selfsense::models {
namespace {

constexpr double kTs = 1e-3;

struct Parts {
  test::TransducerData data;
  TransducerModel plain;      // the typical stack, both sides plain
  TransducerModel vectorial;  // the stress-hysteresis structure fitted on its recording
};

const Parts& parts() {
  static const Parts p = [] {
    Parts out;
    out.plain = test::typical_transducer(kTs);
    out.data = test::transducer_data(out.plain, 4000, 1e-4, 7);
    const test::TransducerData& d = out.data;
    out.vectorial.structure = Structure::kStressHysteresis;
    out.vectorial.sample_time = kTs;
    out.vectorial.vectorial = identification::fit_stress_hysteresis(d.e, d.t, d.d, d.s, kTs, 8);
    // The stack's D is affine in T: a fitted quadratic of noise size could put its vertex in
    // the range, and the solve would then report kNotMonotone (stress_hysteresis.hpp).
    out.vectorial.vectorial->sensor->quadratic = 0.0;
    return out;
  }();
  return p;
}

// The stress structure on one channel, the typical stack's plain side on the other.
TransducerModel mixed(bool stressed_sensor) {
  TransducerModel m = parts().vectorial;
  if (stressed_sensor) {
    m.vectorial->actuator.reset();
    m.actuator = parts().plain.actuator;
  } else {
    m.vectorial->sensor.reset();
    m.sensor = parts().plain.sensor;
  }
  return m;
}

double range_of(const std::vector<double>& x) {
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  return *hi - *lo;
}

// The reconstruction's worst errors against the forward model's T and S, relative to their
// ranges, on the recording's E and T; samples not kOk are counted.
struct RoundTrip {
  double stress{0.0};
  double strain{0.0};
  int not_ok{0};
};

RoundTrip round_trip(const TransducerModel& m) {
  const test::TransducerData& d = parts().data;
  Simulation forward(m);
  Reconstruction rec(m);
  double worst_t = 0.0;
  double worst_s = 0.0;
  RoundTrip r;
  std::vector<double> s(d.e.size());
  for (std::size_t k = 0; k < d.e.size(); ++k) {
    const Simulation::Output out = forward.step(d.e[k], d.t[k]);
    s[k] = out.strain;
    const Reconstruction::Estimate est = rec.step(d.e[k], out.sensed);
    r.not_ok += est.status == SampleStatus::kOk ? 0 : 1;
    worst_t = std::max(worst_t, std::abs(est.stress - d.t[k]));
    worst_s = std::max(worst_s, std::abs(est.strain - out.strain));
  }
  r.stress = worst_t / range_of(d.t);
  r.strain = worst_s / range_of(s);
  return r;
}

TEST(StressSides, EachChannelRunsOnItsOwnPart) {
  const test::TransducerData& d = parts().data;
  for (const bool stressed_sensor : {true, false}) {
    const TransducerModel m = mixed(stressed_sensor);
    std::string why;
    ASSERT_TRUE(m.is_valid(&why)) << why;
    StressSidesForward both(m);
    StressHysteresisForward vectorial(*parts().vectorial.vectorial);
    ForwardModel plain(parts().plain);
    for (std::size_t k = 0; k < d.e.size(); ++k) {
      const StressHysteresisForward::Output out = both.step(d.e[k], d.t[k]);
      const StressHysteresisForward::Output v = vectorial.step(d.e[k], d.t[k]);
      const ForwardModel::Output p = plain.step(d.e[k], d.t[k]);
      ASSERT_EQ(out.sensed, stressed_sensor ? v.sensed : p.sensed) << k;
      ASSERT_EQ(out.strain, stressed_sensor ? p.strain : v.strain) << k;
    }
  }
}

TEST(StressSides, ReconstructionInvertsTheForwardModelWithEitherSensor) {
  for (const bool stressed_sensor : {true, false}) {
    const TransducerModel m = mixed(stressed_sensor);
    ASSERT_TRUE(Reconstruction(m).has_strain());
    const RoundTrip r = round_trip(m);
    // Exact up to rounding: the closed-form solve or eq. 7, then the other side's forward.
    EXPECT_EQ(r.not_ok, 0) << stressed_sensor;
    EXPECT_LT(r.stress, 1e-8) << stressed_sensor;
    EXPECT_LT(r.strain, 1e-8) << stressed_sensor;
  }
}

// A plain sensor beside a stress-dependent actuator keeps what a plain sensor allows: a sensed
// correction with terms in T and a creep of the response to the drive alone (as the affine
// kernel, the stress solved through the correction), and S_hat follows the corrected T_hat. On a
// stress-dependent sensor the same correction is refused by key.
TEST(StressSides, APlainSensorTakesASensedCorrectionWithStressTerms) {
  TransducerModel m = mixed(false);
  ChannelCorrection c;
  c.gain = 0.01;
  c.stress_linear_per_pa = 2e-12;
  c.creep_eigenvalues = {2.0};
  c.creep_weights = {0.02};
  m.sensed_correction = c;
  const RoundTrip r = round_trip(m);
  EXPECT_EQ(r.not_ok, 0);
  EXPECT_LT(r.stress, 1e-8);
  EXPECT_LT(r.strain, 1e-8);
  TransducerModel stressed_sensor = mixed(true);
  stressed_sensor.sensed_correction = c;
  try {
    Reconstruction refused(stressed_sensor);
    ADD_FAILURE() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("corrections.sensed.creep_weights"), std::string::npos)
        << e.what();
  }
}

// A plain side given where the vectorial section has one is refused, by key.
TEST(StressSides, APlainSideOnlyCompletesTheVectorialModel) {
  TransducerModel m = parts().vectorial;
  m.actuator = parts().plain.actuator;
  std::string why;
  EXPECT_FALSE(m.is_valid(&why));
  EXPECT_NE(why.find("actuator: the vectorial section has this side already"), std::string::npos)
      << why;
  TransducerModel no_sensor = mixed(false);
  no_sensor.sensor.reset();
  EXPECT_THROW(Reconstruction{no_sensor}, std::invalid_argument);
}

// Saved at one sample and restored, both parts replay exactly; a reconstruction that adopts a
// running one of the same model (a hot swap) goes on as it would have.
TEST(StressSides, StateAndHotSwapCarryBothParts) {
  const test::TransducerData& d = parts().data;
  for (const bool stressed_sensor : {true, false}) {
    const TransducerModel m = mixed(stressed_sensor);
    Simulation forward(m);
    Reconstruction rec(m);
    std::vector<double> dd(d.e.size());
    for (std::size_t k = 0; k < d.e.size(); ++k)
      dd[k] = forward.step(d.e[k], d.t[k]).sensed;
    constexpr std::size_t kAt = 2000;
    for (std::size_t k = 0; k < kAt; ++k)
      rec.step(d.e[k], dd[k]);
    SavedState saved = rec.make_saved_state();
    ASSERT_TRUE(rec.save_state(saved));
    Reconstruction swapped(m);
    swapped.adopt_state(rec);
    std::vector<Reconstruction::Estimate> first;
    for (std::size_t k = kAt; k < d.e.size(); ++k)
      first.push_back(rec.step(d.e[k], dd[k]));
    ASSERT_EQ(rec.restore_state(saved), RestoreResult::kOk);
    for (std::size_t k = kAt; k < d.e.size(); ++k) {
      const Reconstruction::Estimate again = rec.step(d.e[k], dd[k]);
      const Reconstruction::Estimate after_swap = swapped.step(d.e[k], dd[k]);
      const Reconstruction::Estimate& want = first[k - kAt];
      ASSERT_EQ(again.stress, want.stress) << k;
      ASSERT_EQ(again.strain, want.strain) << k;
      ASSERT_NEAR(after_swap.stress, want.stress, 1e-9 * range_of(d.t)) << k;
      ASSERT_NEAR(after_swap.strain, want.strain, 1e-9 * std::abs(want.strain) + 1e-15) << k;
    }
  }
}

}  // namespace
}  // namespace selfsense::models
