// The drift estimator and the adapted reconstruction on synthetic data whose drift is known:
// convergence, the gates (holds, rejected samples, frozen), the bounds, saved state, and the
// real-time path (no allocation, no lock).
#include "selfsense/adaptation/drift_estimator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "selfsense/adaptation/adapted_reconstruction.hpp"
#include "support/allocation_counter.hpp"
#include "support/transducer_data.hpp"

namespace selfsense::adaptation {
namespace {

static_assert(noexcept(std::declval<DriftEstimator&>().step(0.0, 0.0, 0.0, 0.0, true)));
static_assert(noexcept(std::declval<AdaptedReconstruction&>().step(0.0, 0.0)));

constexpr double kTs = 1e-4;

// The typical transducer whose sensor side drifted by (epsilon, lambda) and coupling by
// `coupling`: E, D, the true T, and the model with the sensed range it would have recorded.
struct Drifted {
  models::TransducerModel model;
  std::vector<double> e, d, t;
};

Drifted drifted(double epsilon, double lambda, double coupling, std::size_t n, std::uint64_t seed) {
  Drifted out{test::typical_transducer(kTs), {}, {}, {}};
  const models::SideModel& sensor = *out.model.sensor;
  models::SideOperator truth(sensor);
  const SideSplit split(truth);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  double lo = 1e300;
  double hi = -1e300;
  for (std::size_t k = 0; k < n; ++k) {
    const double time = static_cast<double>(k) * kTs;
    const double e = 1e6 * (1.0 + 0.9 * std::sin(2 * std::numbers::pi * 3.0 * time) *
                                      std::cos(2 * std::numbers::pi * 0.23 * time));
    const double t = -1e7 * (1.0 + 0.5 * std::sin(2 * std::numbers::pi * 0.2 * time + 0.5));
    const SideSplit::Parts parts = split.split(truth, e, truth.step_unloaded(e) - sensor.offset);
    const double d = sensor.offset + (1.0 + lambda) * parts.loop + (1.0 + epsilon) * parts.linear +
                     (1.0 + coupling) * truth.coupling() * t + 2e-6 * n01(rng);
    out.e.push_back(e + 100.0 * n01(rng));
    out.d.push_back(d);
    out.t.push_back(t);
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  out.model.drive_range = models::InputRange{0.0, 2e6};
  out.model.sensed_range = models::InputRange{lo, hi};
  return out;
}

TEST(DriftEstimatorConfig, NamesTheViolatedKey) {
  std::string why;
  DriftEstimatorConfig c{};
  EXPECT_TRUE(c.is_valid("adaptation.", &why)) << why;
  c.memory_updates = 1.0;
  EXPECT_FALSE(c.is_valid("adaptation.", &why));
  EXPECT_EQ(why, "adaptation.memory_updates: 1 must be > 1");
  c = DriftEstimatorConfig{};
  c.process_noise_per_s = -1e-5;
  EXPECT_FALSE(c.is_valid("adaptation.", &why));
  EXPECT_EQ(why.rfind("adaptation.process_noise_per_s: ", 0), 0U) << why;
  c = DriftEstimatorConfig{};
  c.permittivity_per_k = 0.0;
  EXPECT_FALSE(c.is_valid("adaptation.", &why));
  EXPECT_EQ(why, "adaptation.permittivity_per_k: 0 must not be 0");
  c = DriftEstimatorConfig{};
  c.max_relative_change = std::nan("");
  EXPECT_FALSE(c.is_valid("x.", &why));
  EXPECT_EQ(why, "x.max_relative_change: nan must be finite");
  EXPECT_THROW(DriftEstimator(c, kTs, 1.0), std::invalid_argument);
  EXPECT_THROW(DriftEstimator(DriftEstimatorConfig{}, kTs, 0.0), std::invalid_argument);
}

struct Found {
  Drift drift;
  std::size_t updates;
  double err_adapted, err_plain;  // max |T_hat - T| over the second half [Pa]
};

Found run(const Drifted& data, const DriftEstimatorConfig& config) {
  AdaptedReconstruction rec(data.model, config);
  models::Reconstructor plain(data.model);
  Found f{};
  for (std::size_t k = 0; k < data.e.size(); ++k) {
    const double t_adapted = rec.step(data.e[k], data.d[k]).stress;
    const double t_plain = plain.step(data.e[k], data.d[k]).stress;
    if (k < data.e.size() / 2) continue;  // converged by then
    f.err_adapted = std::max(f.err_adapted, std::abs(t_adapted - data.t[k]));
    f.err_plain = std::max(f.err_plain, std::abs(t_plain - data.t[k]));
  }
  f.drift = rec.drift();
  f.updates = rec.estimator().updates();
  std::printf("max |T_hat - T|: adapted %.3g Pa, as identified %.3g Pa\n", f.err_adapted,
              f.err_plain);
  return f;
}

// A 20 K rise with the default coefficients: permittivity +8 %, loop -8 %, coupling +4 %. The
// one learned parameter finds it: the equivalent temperature is 25 + 0.08 / 0.004 = 45 degC,
// and the stress comes back with the coupling's drift applied.
TEST(AdaptedReconstruction, FindsAKnownTemperatureRise) {
  const Found f = run(drifted(0.08, -0.08, 0.04, 200000, 3), DriftEstimatorConfig{});
  EXPECT_NEAR(f.drift.permittivity, 0.08, 0.002);
  EXPECT_DOUBLE_EQ(f.drift.loop, -f.drift.permittivity);
  EXPECT_NEAR(f.drift.temperature_degc, 45.0, 0.5);
  EXPECT_NEAR(f.drift.coupling, 0.04, 0.001);
  EXPECT_GT(f.updates, 1000U);
  EXPECT_LT(f.err_adapted, 0.1 * f.err_plain);
}

// With learn_loop, a loop that softened less than the coefficients say (-6 % against +8 %
// permittivity) is found as well.
TEST(AdaptedReconstruction, LearnsTheLoopApartWhenAskedTo) {
  DriftEstimatorConfig config{};
  config.learn_loop = true;
  config.memory_updates = 5000.0;
  const Found f = run(drifted(0.08, -0.06, 0.04, 200000, 3), config);
  EXPECT_NEAR(f.drift.permittivity, 0.08, 0.004);
  EXPECT_NEAR(f.drift.loop, -0.06, 0.01);
  EXPECT_NEAR(f.drift.temperature_degc, 45.0, 1.0);
  EXPECT_LT(f.err_adapted, 0.1 * f.err_plain);
}

// A measured temperature replaces the estimate and the estimator learns nothing meanwhile (the
// daemon's adaptation.use_temperature); cleared, it learns on from there and finds the rise.
TEST(AdaptedReconstruction, LearnsNothingWhileAMeasuredTemperatureHolds) {
  const Drifted data = drifted(0.08, -0.08, 0.04, 200000, 3);
  AdaptedReconstruction rec(data.model, DriftEstimatorConfig{});
  const std::size_t half = data.e.size() / 2;
  for (std::size_t k = 0; k < half; ++k) {
    rec.set_temperature(30.0);
    static_cast<void>(rec.step(data.e[k], data.d[k]));
  }
  EXPECT_EQ(rec.estimator().updates(), 0U);
  EXPECT_DOUBLE_EQ(rec.drift().temperature_degc, 30.0);
  rec.set_temperature(std::nan(""));  // ignored: still 30 degC
  EXPECT_DOUBLE_EQ(rec.drift().temperature_degc, 30.0);
  rec.clear_temperature();
  for (std::size_t k = half; k < data.e.size(); ++k)
    static_cast<void>(rec.step(data.e[k], data.d[k]));
  EXPECT_GT(rec.estimator().updates(), 1000U);
  EXPECT_NEAR(rec.drift().temperature_degc, 45.0, 0.5);
}

TEST(DriftEstimator, LearnsNothingOnHoldsRejectedSamplesOrWhenFrozen) {
  DriftEstimator est(DriftEstimatorConfig{}, kTs, 2e-8);
  // A hold: the field within noise of one value.
  for (int k = 0; k < 100000; ++k)
    EXPECT_FALSE(est.step(1e6 + 100.0 * std::sin(k), 0.03, 2e-2, 0.01, true));
  EXPECT_EQ(est.updates(), 0U);
  // Alternating rejected samples: no increment spans one.
  for (int k = 0; k < 1000; ++k) {
    const double e = 1e6 + 1e5 * (k % 2);
    EXPECT_FALSE(est.step(e, 0.03 + 2.2e-8 * e, 2e-8 * e, 0.01, k % 2 == 0));
  }
  EXPECT_EQ(est.updates(), 0U);
  // Moving with a drift: it learns; frozen, the same data teaches nothing.
  for (int k = 0; k < 1000; ++k) {
    const double e = 1e6 + 1e5 * (k % 2);
    est.step(e, 0.03 + 2.2e-8 * e, 2e-8 * e, 0.01, true);
  }
  EXPECT_GT(est.updates(), 900U);
  EXPECT_NEAR(est.drift().permittivity, 0.1, 1e-3);
  est.set_frozen(true);
  const Drift before = est.drift();
  const std::size_t updates = est.updates();
  for (int k = 0; k < 1000; ++k) {
    const double e = 1e6 + 1e5 * (k % 2);
    est.step(e, 0.03 + 2.6e-8 * e, 2e-8 * e, 0.01, true);
  }
  EXPECT_EQ(est.updates(), updates);
  EXPECT_EQ(est.drift().permittivity, before.permittivity);
}

// The loop's own rejections (runtime/loop.hpp): a sample estimated with learn = false and a
// sample skipped (a driver fault) each leave the estimator without an anchor, so no increment
// spans them; the same field steps without them update every time.
// The drift's random walk (process_noise_per_s): on a hold the estimate does not move at all,
// but the first updates after it weigh more, so a change that happened during the hold is found
// in fewer updates than with the forgetting alone; a large step's update (50 gate steps) does
// not leave it stiff.
TEST(DriftEstimator, AHoldWidensTheCovarianceButDoesNotMoveTheEstimate) {
  const auto learn = [](DriftEstimator& est, double gain, int updates) {
    for (int k = 0; k < updates; ++k) {
      const double e = 1e6 + 1e5 * (k % 2);
      est.step(e, 0.03 + gain * e, 2e-8 * e, 0.01, true);
    }
  };
  const auto after_hold = [&learn](double process_noise) {
    DriftEstimatorConfig c{};
    c.process_noise_per_s = process_noise;
    DriftEstimator est(c, kTs, 2e-8);
    learn(est, 2.2e-8, 5000);          // epsilon 0.1, ending at 1.1e6 V/m
    const auto hold = [&est](int k) {  // a 10 s hold at 1e6 V/m, over which the stack warms
      const double e = 1e6 + 100.0 * std::sin(k);
      return est.step(e, 0.03 + 2.4e-8 * e, 2e-8 * e, 0.01, true);
    };
    EXPECT_TRUE(hold(0));  // the step onto the hold is an update
    const Drift before = est.drift();
    for (int k = 1; k < 100000; ++k)
      EXPECT_FALSE(hold(k));
    EXPECT_EQ(est.drift().permittivity, before.permittivity);
    learn(est, 2.4e-8, 20);  // epsilon 0.2 from then on
    return est.drift().permittivity;
  };
  const double with_walk = after_hold(3e-5);
  const double without = after_hold(0.0);
  std::printf("20 updates after a 10 s hold: epsilon %.4f with the random walk, %.4f without\n",
              with_walk, without);
  EXPECT_GT(with_walk - 0.1, 2.0 * (without - 0.1));
  EXPECT_LT(with_walk, 0.2 + 1e-9);
}

// The feedforward's scales (feedforward_scales): 1 as identified; at a measured temperature
// with fitted coefficients, the actuator's response between its linear and loop scales, and
// its compliance scale.
TEST(AdaptedReconstruction, TheFeedforwardScalesFollowAMeasuredTemperature) {
  const Drifted data = drifted(0.0, 0.0, 0.0, 2000, 3);
  models::TransducerModel m = data.model;
  AdaptedReconstruction plain(m, DriftEstimatorConfig{});
  static_cast<void>(plain.step(data.e[1000], data.d[1000]));
  EXPECT_DOUBLE_EQ(plain.feedforward_scales().response, 1.0);
  EXPECT_DOUBLE_EQ(plain.feedforward_scales().compliance, 1.0);
  models::TemperatureCoefficients t{};
  t.actuator.linear.per_k = 2e-3;
  t.actuator.loop.per_k = -4e-3;
  t.actuator.coupling.per_k = 5e-4;
  m.temperature = t;
  AdaptedReconstruction rec(m, DriftEstimatorConfig{});
  for (std::size_t k = 0; k < data.e.size(); ++k) {
    rec.set_temperature(45.0);
    static_cast<void>(rec.step(data.e[k], data.d[k]));
  }
  const AdaptedReconstruction::FeedforwardScales g = rec.feedforward_scales();
  EXPECT_GT(g.response, 1.0 - 0.08 - 1e-12);  // between the loop's 0.92 ...
  EXPECT_LT(g.response, 1.0 + 0.04 + 1e-12);  // ... and the linear part's 1.04
  EXPECT_NE(g.response, 1.0);
  EXPECT_DOUBLE_EQ(g.compliance, 1.0 + 5e-4 * 20.0);
}

TEST(AdaptedReconstruction, LearnsNothingAcrossSamplesTheLoopRejects) {
  const Drifted data = drifted(0.08, -0.08, 0.04, 4000, 7);
  AdaptedReconstruction plain(data.model, DriftEstimatorConfig{});
  AdaptedReconstruction gated(data.model, DriftEstimatorConfig{});
  AdaptedReconstruction skipped(data.model, DriftEstimatorConfig{});
  for (std::size_t k = 0; k < data.e.size(); ++k) {
    static_cast<void>(plain.step(data.e[k], data.d[k]));
    // Every other sample rejected by the loop, or missing.
    static_cast<void>(gated.step(data.e[k], data.d[k], k % 2 == 0));
    if (k % 2 == 0) {
      static_cast<void>(skipped.step(data.e[k], data.d[k]));
    } else {
      skipped.skip();
    }
  }
  EXPECT_GT(plain.estimator().updates(), 100U);
  EXPECT_EQ(gated.estimator().updates(), 0U);
  EXPECT_EQ(skipped.estimator().updates(), 0U);
}

TEST(DriftEstimator, StaysWithinItsBounds) {
  DriftEstimatorConfig c{};
  c.max_relative_change = 0.2;
  DriftEstimator est(c, kTs, 2e-8);
  for (int k = 0; k < 2000; ++k) {
    const double e = 1e6 + 1e5 * (k % 2);
    est.step(e, 0.03 + 4e-8 * e, 2e-8 * e, 0.0, true);  // a doubled permittivity
  }
  EXPECT_DOUBLE_EQ(est.drift().permittivity, 0.2);
  EXPECT_DOUBLE_EQ(est.drift().temperature_degc, 25.0 + 0.2 / 4e-3);
}

TEST(AdaptedReconstruction, SavedStateResumesExactly) {
  const Drifted data = drifted(0.05, -0.03, 0.02, 60000, 4);
  AdaptedReconstruction a(data.model, DriftEstimatorConfig{});
  AdaptedReconstruction b(data.model, DriftEstimatorConfig{});
  std::vector<double> state(a.state_size());
  EXPECT_FALSE(a.save_state(std::span<double>(state).first(3)));
  for (std::size_t k = 0; k < 30000; ++k)
    a.step(data.e[k], data.d[k]);
  ASSERT_TRUE(a.save_state(state));
  ASSERT_TRUE(b.restore_state(state));
  EXPECT_EQ(b.drift().permittivity, a.drift().permittivity);
  for (std::size_t k = 30000; k < data.e.size(); ++k) {
    const auto ea = a.step(data.e[k], data.d[k]);
    const auto eb = b.step(data.e[k], data.d[k]);
    ASSERT_EQ(ea.stress, eb.stress) << k;
    ASSERT_EQ(ea.strain, eb.strain) << k;
  }
  EXPECT_EQ(a.estimator().updates(), b.estimator().updates());
}

// A restart resumes the learned drift only into the same model: a state of another model or a
// plain Reconstruction's state of this one is refused and changes nothing.
TEST(AdaptedReconstruction, SavedStateCarriesTheModelsIdentity) {
  const Drifted data = drifted(0.05, -0.05, 0.025, 40000, 7);
  AdaptedReconstruction a(data.model, DriftEstimatorConfig{});
  for (std::size_t k = 0; k < data.e.size(); ++k)
    a.step(data.e[k], data.d[k]);
  models::SavedState saved = a.make_saved_state();
  ASSERT_TRUE(a.save_state(saved));
  AdaptedReconstruction b(data.model, DriftEstimatorConfig{});
  EXPECT_EQ(b.restore_state(saved), models::RestoreResult::kOk);
  EXPECT_EQ(b.drift().temperature_degc, a.drift().temperature_degc);
  EXPECT_GT(b.drift().temperature_degc, 30.0);

  models::TransducerModel other = data.model;
  other.sensor->offset += 1e-4;
  AdaptedReconstruction c(other, DriftEstimatorConfig{});
  EXPECT_EQ(c.restore_state(saved), models::RestoreResult::kWrongModel);
  EXPECT_EQ(c.drift().temperature_degc, 25.0);

  const models::Reconstruction plain(data.model);
  EXPECT_EQ(b.restore_state(plain.make_saved_state()), models::RestoreResult::kWrongSize);
  models::SavedState wrong = b.make_saved_state();
  wrong.values.pop_back();
  EXPECT_FALSE(b.save_state(wrong));
}

TEST(AdaptedReconstruction, RejectsSpikesAndLearnsNothingFromThem) {
  const Drifted data = drifted(0.05, -0.03, 0.02, 20000, 5);
  AdaptedReconstruction rec(data.model, DriftEstimatorConfig{});
  for (std::size_t k = 0; k < 10000; ++k)
    rec.step(data.e[k], data.d[k]);
  const std::size_t updates = rec.estimator().updates();
  const auto spike = rec.step(20e6, data.d[10000]);
  EXPECT_EQ(spike.status, models::SampleStatus::kInputOutOfRange);
  EXPECT_EQ(rec.estimator().updates(), updates);
  EXPECT_EQ(rec.step(std::nan(""), 0.0).status, models::SampleStatus::kInputNotFinite);
  EXPECT_EQ(rec.counts()[models::SampleStatus::kInputOutOfRange], 1U);
}

// On a load spring (the daemon's bench: r = k_load / k_stack = 0.21) the stress follows the
// field: T = -(r / s) / (1 + r) S_free, s the compliance, S_free the drifted actuator's free
// strain. Taken as independent of the field, that stress is learned as permittivity (the
// estimate is pulled far from +8 %); with the mount's ratio it is found as on a free stack.
TEST(AdaptedReconstruction, FindsTheRiseOnALoadSpringWithTheMountsRatio) {
  constexpr double kRatio = 0.21;
  Drifted data = drifted(0.08, -0.08, 0.04, 200000, 5);
  const models::SideModel& sensor = *data.model.sensor;
  const models::SideModel& actuator = *data.model.actuator;
  models::SideOperator sensor_truth(sensor);
  models::SideOperator actuator_truth(actuator);
  const SideSplit sensor_split(sensor_truth);
  const SideSplit actuator_split(actuator_truth);
  const double gain = -(kRatio / actuator_truth.coupling()) / (1.0 + kRatio);
  double lo = 1e300;
  double hi = -1e300;
  for (std::size_t k = 0; k < data.e.size(); ++k) {
    const double e = data.e[k];
    const SideSplit::Parts ps =
        sensor_split.split(sensor_truth, e, sensor_truth.step_unloaded(e) - sensor.offset);
    const SideSplit::Parts pa =
        actuator_split.split(actuator_truth, e, actuator_truth.step_unloaded(e) - actuator.offset);
    const double t = gain * (actuator.offset + 1.04 * pa.linear + 0.92 * pa.loop);
    data.t[k] = t;
    data.d[k] =
        sensor.offset + 0.92 * ps.loop + 1.08 * ps.linear + 1.04 * sensor_truth.coupling() * t;
    lo = std::min(lo, data.d[k]);
    hi = std::max(hi, data.d[k]);
  }
  data.model.sensed_range = models::InputRange{lo, hi};
  const Found free = run(data, DriftEstimatorConfig{});
  EXPECT_GT(std::abs(free.drift.permittivity - 0.08), 0.02);  // the spring, learned as drift
  DriftEstimatorConfig mounted{};
  mounted.load_stiffness_ratio = kRatio;
  // Found to 0.0756 (43.9 degC): the mount's stress is predicted from the model's free strain,
  // not the drifted one (+4 % coupling, -8 % loop), a second-order error; asserted at 1.3x.
  const Found f = run(data, mounted);
  EXPECT_NEAR(f.drift.permittivity, 0.08, 0.006);
  EXPECT_NEAR(f.drift.temperature_degc, 45.0, 1.5);
  EXPECT_LT(f.err_adapted, 0.2 * free.err_adapted);
  DriftEstimatorConfig bad{};
  bad.load_stiffness_ratio = -0.1;
  std::string why;
  EXPECT_FALSE(bad.is_valid("adaptation.", &why));
  EXPECT_EQ(why, "adaptation.load_stiffness_ratio: -0.1 must be >= 0");
}

TEST(AdaptedReconstruction, RefusesWhatItCannotAdapt) {
  models::TransducerModel m = test::typical_transducer(kTs);
  m.sensor->linear_gains = {0.0};
  EXPECT_THROW(AdaptedReconstruction(m, DriftEstimatorConfig{}), std::invalid_argument);
  m = test::typical_transducer(kTs);
  EXPECT_NO_THROW(AdaptedReconstruction(m, DriftEstimatorConfig{}));
  m.sensed_correction = models::ChannelCorrection{};
  EXPECT_THROW(AdaptedReconstruction(m, DriftEstimatorConfig{}), std::invalid_argument);
}

// The real-time path: the adapted step, the estimator alone and the state saves allocate
// nothing and take no lock.
TEST(AdaptationRealTime, StepsAndStateSavesDoNotAllocateOrLock) {
  const Drifted data = drifted(0.05, -0.03, 0.02, 5000, 6);
  AdaptedReconstruction rec(data.model, DriftEstimatorConfig{});
  DriftEstimator est(DriftEstimatorConfig{}, kTs, 2e-8);
  models::Reconstructor plain(data.model);
  const SideSplit split(*plain.sensor());
  std::vector<double> state(rec.state_size());
  models::SavedState saved = rec.make_saved_state();
  std::vector<double> est_state(DriftEstimator::state_size());
  double sink = 0.0;
  test::AllocationCounter counter;
  for (std::size_t k = 0; k < data.e.size(); ++k) {
    const AdaptedReconstruction::Estimate out = rec.step(data.e[k], data.d[k]);
    rec.save_state(state);
    rec.restore_state(state);
    rec.save_state(saved);
    sink += static_cast<double>(rec.restore_state(saved));
    est.step(data.e[k], data.d[k], 2e-8 * data.e[k], 0.0, k % 7 != 0);
    sink += split.split(*plain.sensor(), data.e[k], plain.sensor()->step_unloaded(data.e[k])).loop;
    est.save_state(est_state);
    est.restore_state(est_state);
    sink += out.stress + out.strain + rec.drift().temperature_degc + est.drift().loop;
  }
  EXPECT_EQ(counter.count(), 0U);
  EXPECT_EQ(counter.locks(), 0U);
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
}  // namespace selfsense::adaptation
