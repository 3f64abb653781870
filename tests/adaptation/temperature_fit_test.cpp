// The temperature coefficients (adaptation/temperature_fit.hpp) on synthetic data whose drift is
// known: a typical transducer whose parts scale with a temperature ramp by given polynomials.
// The fit recovers them, the adapted reconstruction with them and the measured temperature
// recovers T and S, and nothing allocates per sample.
#include "selfsense/adaptation/temperature_fit.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "selfsense/adaptation/adapted_reconstruction.hpp"
#include "support/allocation_counter.hpp"
#include "support/transducer_data.hpp"

namespace selfsense::adaptation {
namespace {

constexpr double kTs = 1e-4;

struct Ramp {
  models::TransducerModel model;
  std::vector<double> e, d, t, s, temp;
};

// The truth: sensor L +4e-3/K -2e-6/K^2, H -4e-3/K +3e-6/K^2, d +2e-3/K; actuator L +2e-3/K,
// H -4e-3/K, s +5e-4/K +1e-6/K^2; about 25 degC, warming 25 -> 55 degC.
models::TemperatureCoefficients truth() {
  models::TemperatureCoefficients c;
  c.reference_degc = 25.0;
  c.sensor = {{4e-3, -2e-6}, {-4e-3, 3e-6}, {2e-3, 0.0}};
  c.actuator = {{2e-3, 0.0}, {-4e-3, 0.0}, {5e-4, 1e-6}};
  return c;
}

// From `from` to `to` degC over the n samples (one temperature where they are equal).
Ramp ramp(std::size_t n, double from = 25.0, double to = 55.0) {
  Ramp out{test::typical_transducer(kTs), {}, {}, {}, {}, {}};
  const models::TemperatureCoefficients c = truth();
  models::SideOperator sensor(*out.model.sensor);
  models::SideOperator actuator(*out.model.actuator);
  const SideSplit split_s(sensor);
  const SideSplit split_a(actuator);
  double lo = 1e300;
  double hi = -1e300;
  for (std::size_t k = 0; k < n; ++k) {
    const double time = static_cast<double>(k) * kTs;
    const double e = 1e6 * (1.0 + 0.9 * std::sin(2 * std::numbers::pi * 3.0 * time) *
                                      std::cos(2 * std::numbers::pi * 0.23 * time));
    const double t = -1e7 * (1.0 + 0.5 * std::sin(2 * std::numbers::pi * 0.7 * time + 0.5));
    const double temp = from + (to - from) * static_cast<double>(k) / static_cast<double>(n);
    const double dt = temp - c.reference_degc;
    const SideSplit::Parts ps =
        split_s.split(sensor, e, sensor.step_unloaded(e) - out.model.sensor->offset);
    const SideSplit::Parts pa =
        split_a.split(actuator, e, actuator.step_unloaded(e) - out.model.actuator->offset);
    const double d = out.model.sensor->offset + c.sensor.linear.scale(dt) * ps.linear +
                     c.sensor.loop.scale(dt) * ps.loop +
                     c.sensor.coupling.scale(dt) * sensor.coupling() * t;
    const double s = out.model.actuator->offset + c.actuator.linear.scale(dt) * pa.linear +
                     c.actuator.loop.scale(dt) * pa.loop +
                     c.actuator.coupling.scale(dt) * actuator.coupling() * t;
    out.e.push_back(e);
    out.d.push_back(d);
    out.t.push_back(t);
    out.s.push_back(s);
    out.temp.push_back(temp);
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  out.model.drive_range = models::InputRange{0.0, 2e6};
  out.model.sensed_range = models::InputRange{lo, hi};
  return out;
}

void expect_polynomial(const models::TemperaturePolynomial& fitted,
                       const models::TemperaturePolynomial& want) {
  EXPECT_NEAR(fitted.per_k, want.per_k, 1e-7);
  EXPECT_NEAR(fitted.per_k2, want.per_k2, 1e-8);
}

void expect_coefficients(const models::TemperatureCoefficients& fitted,
                         const models::TemperatureCoefficients& want) {
  for (const auto side :
       {&models::TemperatureCoefficients::sensor, &models::TemperatureCoefficients::actuator}) {
    expect_polynomial((fitted.*side).linear, (want.*side).linear);
    expect_polynomial((fitted.*side).loop, (want.*side).loop);
    expect_polynomial((fitted.*side).coupling, (want.*side).coupling);
  }
}

TEST(TemperatureFit, RecoversKnownCoefficients) {
  const Ramp r = ramp(40000);
  const TemperatureFitResult fit = fit_temperature(r.model, {r.e, r.d, r.t, r.s, r.temp}, 25.0);
  const models::TemperatureCoefficients want = truth();
  EXPECT_EQ(fit.samples, r.e.size());
  EXPECT_TRUE(fit.quadratic);
  EXPECT_EQ(fit.coefficients.reference_degc, 25.0);
  expect_coefficients(fit.coefficients, want);
  EXPECT_LT(fit.sensor_rms_after, 1e-6 * fit.sensor_rms_before);
  EXPECT_LT(fit.actuator_rms_after, 1e-6 * fit.actuator_rms_before);
  // On the estimator's increments the synthetic sensor's drift is the levels' (its parts scale
  // as a whole), to first order and as far as the increments tell L from H (measured 3.87e-3
  // and -3.68e-3 per K): within 10 %.
  EXPECT_GT(fit.increments, 1000U);
  EXPECT_NEAR(fit.coefficients.increments.linear_per_k, want.sensor.linear.per_k, 4e-4);
  EXPECT_NEAR(fit.coefficients.increments.loop_per_k, want.sensor.loop.per_k, 4e-4);
  // First order only: the quadratic terms are left out.
  const TemperatureFitResult linear =
      fit_temperature(r.model, {r.e, r.d, r.t, r.s, r.temp}, 25.0, false);
  EXPECT_EQ(linear.coefficients.sensor.linear.per_k2, 0.0);
  EXPECT_GT(linear.sensor_rms_after, fit.sensor_rms_after);
}

// Recordings each held at one temperature fit together what the ramp over their range fits; each
// alone spans no temperature and is refused.
TEST(TemperatureFit, RecordingsAtSeveralFixedTemperaturesFitTogether) {
  const Ramp at25 = ramp(20000, 25.0, 25.0);
  const Ramp at40 = ramp(20000, 40.0, 40.0);
  const Ramp at55 = ramp(20000, 55.0, 55.0);
  std::vector<TemperatureFitInput> recordings;
  for (const Ramp* r : {&at25, &at40, &at55})
    recordings.push_back({r->e, r->d, r->t, r->s, r->temp});
  const TemperatureFitResult fit = fit_temperature(at25.model, recordings, 25.0);
  const models::TemperatureCoefficients want = truth();
  EXPECT_EQ(fit.samples, 60000U);
  EXPECT_TRUE(fit.quadratic);  // three temperatures
  expect_coefficients(fit.coefficients, want);
  EXPECT_LT(fit.sensor_rms_after, 1e-6 * fit.sensor_rms_before);
  for (const TemperatureFitInput& one : recordings) {
    EXPECT_THROW(static_cast<void>(fit_temperature(at25.model, one, 25.0)), std::invalid_argument);
  }
  // Two temperatures, 30 K apart: the first order only, though the quadratic terms were asked
  // for; the secant of each part's scale (the reference recording's rows carry no drift),
  // 4e-3 - 2e-6 * 30 per K for the permittivity.
  const TemperatureFitResult secant =
      fit_temperature(at25.model, {recordings[0], recordings[2]}, 25.0);
  EXPECT_FALSE(secant.quadratic);
  EXPECT_NEAR(secant.coefficients.sensor.linear.per_k, 4e-3 - 2e-6 * 30.0, 1e-7);
  EXPECT_NEAR(secant.coefficients.sensor.loop.per_k, -4e-3 + 3e-6 * 30.0, 1e-7);
  // A recording whose columns differ in length is named by its index.
  recordings[1].strain = recordings[1].strain.first(100);
  try {
    static_cast<void>(fit_temperature(at25.model, recordings, 25.0));
    ADD_FAILURE() << "a recording with columns of different lengths was fitted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("recording 1"), std::string::npos) << e.what();
  }
}

TEST(TemperatureFit, RefusesWhatItCannotFit) {
  const Ramp r = ramp(2000);
  const std::vector<double> flat(r.e.size(), 30.0);
  EXPECT_THROW(static_cast<void>(fit_temperature(r.model, {r.e, r.d, r.t, r.s, flat}, 25.0)),
               std::invalid_argument);
  const std::span<const double> shorter = std::span<const double>(r.s).first(100);
  EXPECT_THROW(static_cast<void>(fit_temperature(r.model, {r.e, r.d, r.t, shorter, r.temp}, 25.0)),
               std::invalid_argument);
  models::TransducerModel one_side = r.model;
  one_side.actuator.reset();
  EXPECT_THROW(static_cast<void>(fit_temperature(one_side, {r.e, r.d, r.t, r.s, r.temp}, 25.0)),
               std::invalid_argument);
}

// With the coefficients in the model and the measured temperature, T and S come back (to the
// rounding of the synthetic data); without the coefficients (the estimator's defaults, which
// leave out the quadratic terms and the actuator's own loop) they do not as well.
TEST(TemperatureFit, TheAdaptedReconstructionUsesThemWithAMeasuredTemperature) {
  Ramp r = ramp(40000);
  DriftEstimatorConfig config{};
  config.frozen = true;
  AdaptedReconstruction without(r.model, config);
  r.model.temperature = truth();
  AdaptedReconstruction with(r.model, config);
  EXPECT_TRUE(with.has_temperature_coefficients());
  double err_with = 0.0;
  double err_without = 0.0;
  double err_strain = 0.0;
  test::AllocationCounter counter;
  for (std::size_t k = 0; k < r.e.size(); ++k) {
    with.set_temperature(r.temp[k]);
    without.set_temperature(r.temp[k]);
    const AdaptedReconstruction::Estimate a = with.step(r.e[k], r.d[k]);
    const AdaptedReconstruction::Estimate b = without.step(r.e[k], r.d[k]);
    err_with = std::max(err_with, std::abs(a.stress - r.t[k]));
    err_without = std::max(err_without, std::abs(b.stress - r.t[k]));
    err_strain = std::max(err_strain, std::abs(a.strain - r.s[k]));
  }
  EXPECT_EQ(counter.count(), 0U);
  EXPECT_LT(err_with, 1.0);  // [Pa], of a stress of about 1e7 Pa
  EXPECT_LT(err_strain, 1e-12);
  EXPECT_GT(err_without, 1e3 * err_with);
  // Cleared, the estimate (here frozen at the last measured temperature) serves again.
  with.clear_temperature();
  EXPECT_NEAR(with.drift().temperature_degc, r.temp.back(), 1e-6);
}

// With the increments' coefficients (models::IncrementTemperature) the estimator is read through
// them: a measured temperature sets epsilon = i_L dtheta and lambda = i_H dtheta, the equivalent
// temperature is epsilon / i_L, and learning from E and D alone (every scale a level polynomial
// there) allocates nothing per sample and follows the synthetic ramp up.
TEST(TemperatureFit, TheIncrementsCoefficientsReadTheEstimate) {
  Ramp r = ramp(40000);
  const TemperatureFitResult fit = fit_temperature(r.model, {r.e, r.d, r.t, r.s, r.temp}, 25.0);
  ASSERT_TRUE(fit.coefficients.increments.fitted());
  r.model.temperature = fit.coefficients;
  AdaptedReconstruction measured(r.model, DriftEstimatorConfig{});
  measured.set_temperature(40.0);
  EXPECT_DOUBLE_EQ(measured.drift().permittivity, 15.0 * fit.coefficients.increments.linear_per_k);
  EXPECT_DOUBLE_EQ(measured.drift().loop, 15.0 * fit.coefficients.increments.loop_per_k);
  EXPECT_NEAR(measured.drift().temperature_degc, 40.0, 1e-9);
  AdaptedReconstruction learned(r.model, DriftEstimatorConfig{});
  test::AllocationCounter counter;
  for (std::size_t k = 0; k < r.e.size(); ++k)
    static_cast<void>(learned.step(r.e[k], r.d[k]));
  EXPECT_EQ(counter.count(), 0U);
  EXPECT_GT(learned.estimator().updates(), 1000U);
  const Drift dr = learned.drift();
  EXPECT_DOUBLE_EQ(dr.temperature_degc,
                   25.0 + dr.permittivity / fit.coefficients.increments.linear_per_k);
  // The synthetic ramp is fast (30 K in 4 s) and its stress moves a lot: the estimate follows
  // it with a lag (measured 45.4 degC at the end of the ramp to 55 degC).
  EXPECT_GT(dr.temperature_degc, 40.0);
  EXPECT_LT(dr.temperature_degc, r.temp.back());
}

}  // namespace
}  // namespace selfsense::adaptation
