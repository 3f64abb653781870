#include "selfsense/identification/stress_hysteresis_fit.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <stdexcept>
#include <vector>

#include "selfsense/identification/nnls.hpp"

namespace selfsense::identification {
namespace {

using RowBlock = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Columns: q (W0, bounded), t q (W1), t, t^2, 1.
models::StressHysteresisSide fit_side(const operators::OperatorBasis& basis,
                                      std::span<const double> history, std::span<const double> e,
                                      std::span<const double> t, std::span<const double> y) {
  const std::size_t p = basis.columns();
  const auto cols = static_cast<Eigen::Index>(2 * p + 3);
  GramAccumulator acc(cols);
  operators::RegressorStream stream(basis, history);
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
  const BoundedLeastSquaresSolution sol =
      solve_bounded_least_squares({acc.gram(), acc.moment(), acc.output_energy(), bounded, lower});
  models::StressHysteresisSide side;
  side.base.assign(sol.theta.data(), sol.theta.data() + p);
  side.stress.assign(sol.theta.data() + p, sol.theta.data() + 2 * p);
  side.linear = sol.theta(cols - 3);
  side.quadratic = sol.theta(cols - 2);
  side.offset = sol.theta(cols - 1);
  return side;
}

}  // namespace

models::StressHysteresisModel fit_stress_hysteresis(std::span<const double> e,
                                                    std::span<const double> t,
                                                    std::span<const double> d,
                                                    std::span<const double> s, double sample_time,
                                                    std::size_t plays) {
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
  models::StressHysteresisModel m;
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

}  // namespace selfsense::identification
