#include "selfsense/models/stress_hysteresis.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "selfsense/operators/kernels.hpp"
#include "selfsense/operators/parameter_error.hpp"

namespace selfsense::models {

double StressHysteresisSide::evaluate(std::span<const double> q, double t) const noexcept {
  return operators::kernels::dot(base, q) + t * operators::kernels::dot(stress, q) +
         (linear + quadratic * t) * t + offset;
}

bool StressHysteresisModel::is_valid(std::string* why) const {
  namespace check = operators::check;  // base::check
  if (basis.thresholds.empty() || basis.thresholds.front() != 0.0) {
    return check::fail("vectorial.thresholds", "must start with 0 (the linear term)", why);
  }
  if (!operators::check::strictly_increasing_above(
          "vectorial.thresholds", std::span(basis.thresholds).subspan(1), 0.0, why)) {
    return false;
  }
  if (!basis.hinge_rows.empty())
    return check::fail("vectorial", "hinges are not part of this model", why);
  for (std::size_t i = 0; i < basis.creep_rows.size(); ++i) {
    if (basis.creep_rows[i] >= basis.plays() ||
        (i > 0 && basis.creep_rows[i] <= basis.creep_rows[i - 1])) {
      return check::fail("vectorial.creep.rows",
                         "must be increasing play indices below " + std::to_string(basis.plays()),
                         why);
    }
  }
  if (basis.creep_rows.empty() != basis.eigenvalues.empty()) {
    return check::fail("vectorial.creep",
                       "rows and eigenvalues must both be given or both be empty", why);
  }
  for (const double l : basis.eigenvalues) {
    if (!(l > 0.0) || !std::isfinite(l)) {
      return check::fail("vectorial.creep.eigenvalues", "must be finite and > 0", why);
    }
  }
  if (!(stress_max > stress_min)) {
    return check::fail("vectorial.stress_range", "max must be > min", why);
  }
  for (const auto& [name, side] :
       {std::pair{"sensor", &sensor}, std::pair{"actuator", &actuator}}) {
    if (!*side) continue;
    const std::string prefix = std::string("vectorial.") + name;
    const char* columns =
        basis.creep() > 0 ? "vectorial's plays and creep lags" : "vectorial.thresholds";
    if (!operators::check::same_size(prefix + ".base", (*side)->base.size(), columns,
                                     basis.columns(), why) ||
        !operators::check::same_size(prefix + ".stress", (*side)->stress.size(), columns,
                                     basis.columns(), why) ||
        !operators::check::all_finite(prefix + ".base", (*side)->base, why) ||
        !operators::check::all_finite(prefix + ".stress", (*side)->stress, why) ||
        !operators::check::finite(prefix + ".linear", (*side)->linear, why) ||
        !operators::check::finite(prefix + ".quadratic", (*side)->quadratic, why) ||
        !operators::check::finite(prefix + ".offset", (*side)->offset, why)) {
      return false;
    }
  }
  return true;
}

StressHysteresisModel with_creep_gains(StressHysteresisModel model) {
  model.basis.gains.clear();
  for (const double l : model.basis.eigenvalues)
    model.basis.gains.push_back(-std::expm1(-l * model.sample_time));
  return model;
}

StressHysteresisForward::StressHysteresisForward(StressHysteresisModel model)
    : model_(with_creep_gains(std::move(model))), stream_(model_.basis, model_.history) {}

StressHysteresisForward::Output StressHysteresisForward::step(double e, double t) noexcept {
  const std::span<const double> q = stream_.next(e);
  Output out{std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()};
  if (model_.sensor) out.sensed = model_.sensor->evaluate(q, t);
  if (model_.actuator) out.strain = model_.actuator->evaluate(q, t);
  return out;
}

namespace {

struct StressSolution {
  double stress{0.0};
  SampleStatus status{SampleStatus::kOk};
};

// c T^2 + b T + (a - d) = 0 on the branch of the identified range [lo, hi] (header comment).
StressSolution solve_quadratic_stress(double a, double b, double c, double d, double lo,
                                      double hi) noexcept {
  const double mid = 0.5 * (lo + hi);
  const double f0 = a - d;
  // |c| T^2 negligible against |b| T over the whole range: D is affine in T there.
  const double reach = std::max(std::abs(lo), std::abs(hi));
  if (std::abs(c) * reach <= 1e-12 * std::abs(b)) {
    if (b == 0.0) return {mid, SampleStatus::kNoSolution};
    return {-f0 / b, SampleStatus::kOk};
  }
  const double vertex = -b / (2.0 * c);
  const SampleStatus shape =
      (vertex > lo && vertex < hi) ? SampleStatus::kNotMonotone : SampleStatus::kOk;
  const double disc = b * b - 4.0 * c * f0;
  if (!(disc >= 0.0)) return {vertex, SampleStatus::kNoSolution};
  const double slope_sign = (b + 2.0 * c * mid) >= 0.0 ? 1.0 : -1.0;
  const double root = std::sqrt(disc);
  // The branch root (-b + s root) / 2c, in the form that does not cancel.
  const bool same_sign_as_b = (b >= 0.0) == (slope_sign > 0.0);
  const double t =
      same_sign_as_b ? -2.0 * f0 / (b + slope_sign * root) : (-b + slope_sign * root) / (2.0 * c);
  return {t, shape};
}

}  // namespace

StressHysteresisReconstructor::StressHysteresisReconstructor(StressHysteresisModel model)
    : model_(with_creep_gains(std::move(model))), stream_(model_.basis, model_.history) {
  if (!model_.sensor) {
    throw std::invalid_argument("stress-hysteresis reconstruction needs a sensor side");
  }
}

StressHysteresisReconstructor::Estimate StressHysteresisReconstructor::step(double e,
                                                                            double d) noexcept {
  const std::span<const double> q = stream_.next(e);
  const StressHysteresisSide& sensor = *model_.sensor;
  const double a = operators::kernels::dot(sensor.base, q) + sensor.offset;
  const double b = operators::kernels::dot(sensor.stress, q) + sensor.linear;
  const StressSolution r =
      solve_quadratic_stress(a, b, sensor.quadratic, d, model_.stress_min, model_.stress_max);
  counts_.add(r.status);
  Estimate out{r.stress, std::numeric_limits<double>::quiet_NaN(), r.status};
  if (model_.actuator) out.strain = model_.actuator->evaluate(q, r.stress);
  return out;
}

}  // namespace selfsense::models
