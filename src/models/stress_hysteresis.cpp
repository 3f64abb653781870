#include "selfsense/models/stress_hysteresis.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <limits>
#include <stdexcept>
#include <utility>

#include "selfsense/identification/nnls.hpp"
#include "selfsense/operators/kernels.hpp"
#include "selfsense/operators/parameter_error.hpp"

namespace selfsense::models {
namespace {

using identification::GramAccumulator;
using RowBlock = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Columns: q (W0, bounded), t q (W1), t, t^2, 1.
StressHysteresisSide fit_side(const identification::OperatorBasis& basis,
                              std::span<const double> history, std::span<const double> e,
                              std::span<const double> t, std::span<const double> y) {
  const std::size_t p = basis.columns();
  const auto cols = static_cast<Eigen::Index>(2 * p + 3);
  GramAccumulator acc(cols);
  identification::RegressorStream stream(basis, history);
  constexpr Eigen::Index kBlock = 512;
  RowBlock block(kBlock, cols);
  Eigen::VectorXd target(kBlock);
  Eigen::Index row = 0;
  for (std::size_t k = 0; k < e.size(); ++k) {
    const std::span<const double> q = stream.next(e[k]);
    for (std::size_t i = 0; i < p; ++i) {
      block(row, static_cast<Eigen::Index>(i)) = q[i];
      block(row, static_cast<Eigen::Index>(p + i)) = t[k] * q[i];
    }
    block(row, cols - 3) = t[k];
    block(row, cols - 2) = t[k] * t[k];
    block(row, cols - 1) = 1.0;
    target(row) = y[k];
    if (++row == kBlock) {
      acc.add(block, target);
      row = 0;
    }
  }
  if (row > 0) acc.add(block.topRows(row), target.head(row));
  std::vector<bool> bounded(static_cast<std::size_t>(cols), false);
  std::fill_n(bounded.begin(), p, true);
  const auto [y_lo, y_hi] = std::minmax_element(y.begin(), y.end());
  const auto [e_lo, e_hi] = std::minmax_element(e.begin(), e.end());
  Eigen::VectorXd lower = Eigen::VectorXd::Zero(cols);
  lower.head(static_cast<Eigen::Index>(p)).setConstant(1e-6 * (*y_hi - *y_lo) / (*e_hi - *e_lo));
  const identification::BoundedLeastSquaresSolution sol =
      identification::solve_bounded_least_squares(
          {acc.gram(), acc.moment(), acc.output_energy(), bounded, lower});
  StressHysteresisSide side;
  side.base.assign(sol.theta.data(), sol.theta.data() + p);
  side.stress.assign(sol.theta.data() + p, sol.theta.data() + 2 * p);
  side.linear = sol.theta(cols - 3);
  side.quadratic = sol.theta(cols - 2);
  side.offset = sol.theta(cols - 1);
  return side;
}

}  // namespace

double StressHysteresisSide::evaluate(std::span<const double> q, double t) const noexcept {
  return operators::kernels::dot(base, q) + t * operators::kernels::dot(stress, q) +
         (linear + quadratic * t) * t + offset;
}

StressHysteresisModel fit_stress_hysteresis(std::span<const double> e, std::span<const double> t,
                                            std::span<const double> d, std::span<const double> s,
                                            double sample_time, std::size_t plays) {
  const std::size_t n = e.size();
  if (n < 2 || t.size() != n || (!d.empty() && d.size() != n) || (!s.empty() && s.size() != n) ||
      (d.empty() && s.empty())) {
    throw std::invalid_argument(
        "fit_stress_hysteresis: E, T and at least one of D, S need the same length >= 2");
  }
  if (!(sample_time > 0.0)) throw std::invalid_argument("fit_stress_hysteresis: sample time <= 0");
  const auto [e_lo, e_hi] = std::minmax_element(e.begin(), e.end());
  const auto [t_lo, t_hi] = std::minmax_element(t.begin(), t.end());
  if (!(*e_hi > *e_lo) || !(*t_hi > *t_lo)) {
    throw std::invalid_argument("fit_stress_hysteresis: E and T must both vary");
  }
  StressHysteresisModel m;
  m.sample_time = sample_time;
  m.basis.thresholds.push_back(0.0);
  for (std::size_t i = 1; i <= plays; ++i) {
    m.basis.thresholds.push_back(0.5 * (*e_hi - *e_lo) * static_cast<double>(i) /
                                 static_cast<double>(plays + 1));
  }
  m.history = {e.front()};
  if (!d.empty()) m.sensor = fit_side(m.basis, m.history, e, t, d);
  if (!s.empty()) m.actuator = fit_side(m.basis, m.history, e, t, s);
  const double span = *t_hi - *t_lo;
  m.stress_min = *t_lo - 0.1 * span;
  m.stress_max = *t_hi + 0.1 * span;
  return m;
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
