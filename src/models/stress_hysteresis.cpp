#include "selfsense/models/stress_hysteresis.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <utility>

#include "selfsense/operators/kernels.hpp"
#include "selfsense/operators/parameter_error.hpp"

namespace selfsense::models {

double StressHysteresisSide::evaluate(std::span<const double> q, double t) const noexcept {
  return operators::kernels::dot(base, q) + t * operators::kernels::dot(stress, q) +
         (linear + quadratic * t) * t + offset;
}

bool StressHysteresisModel::is_valid(std::string* why) const {
  const auto fail = [why](const std::string& message) {
    if (why != nullptr) *why = message;
    return false;
  };
  if (basis.thresholds.empty() || basis.thresholds.front() != 0.0) {
    return fail("vectorial.thresholds: must start with 0 (the linear term)");
  }
  if (!operators::check::strictly_increasing_above(
          "vectorial.thresholds", std::span(basis.thresholds).subspan(1), 0.0, why)) {
    return false;
  }
  if (!basis.creep_rows.empty()) return fail("vectorial: creep is not part of this model");
  if (!(stress_max > stress_min)) return fail("vectorial.stress_range: max must be > min");
  for (const auto& [name, side] :
       {std::pair{"sensor", &sensor}, std::pair{"actuator", &actuator}}) {
    if (!*side) continue;
    const std::string prefix = std::string("vectorial.") + name;
    if (!operators::check::same_size(prefix + ".base", (*side)->base.size(), "vectorial.thresholds",
                                     basis.plays(), why) ||
        !operators::check::same_size(prefix + ".stress", (*side)->stress.size(),
                                     "vectorial.thresholds", basis.plays(), why) ||
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

StressHysteresisForward::StressHysteresisForward(StressHysteresisModel model)
    : model_(std::move(model)), stream_(model_.basis, model_.history) {}

StressHysteresisForward::Output StressHysteresisForward::step(double e, double t) noexcept {
  const std::span<const double> q = stream_.next(e);
  Output out{std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()};
  if (model_.sensor) out.sensed = model_.sensor->evaluate(q, t);
  if (model_.actuator) out.strain = model_.actuator->evaluate(q, t);
  return out;
}

StressHysteresisReconstructor::StressHysteresisReconstructor(StressHysteresisModel model,
                                                             SolverOptions options)
    : model_(std::move(model)), options_(options), stream_(model_.basis, model_.history) {
  if (!model_.sensor) {
    throw std::invalid_argument("stress-hysteresis reconstruction needs a sensor side");
  }
}

StressHysteresisReconstructor::Estimate StressHysteresisReconstructor::step(double e,
                                                                            double d) noexcept {
  const std::span<const double> q = stream_.next(e);
  const StressHysteresisSide& sensor = *model_.sensor;
  const SolveResult r = solve_bracketed([&](double t) { return sensor.evaluate(q, t) - d; },
                                        model_.stress_min, model_.stress_max, options_);
  ++counts_[static_cast<std::size_t>(r.status)];
  Estimate out{r.value, std::numeric_limits<double>::quiet_NaN(), r.status};
  if (model_.actuator) out.strain = model_.actuator->evaluate(q, r.value);
  return out;
}

}  // namespace selfsense::models
