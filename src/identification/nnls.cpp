#include "selfsense/identification/nnls.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace selfsense::identification {
namespace {

// Solves the unconstrained problem on the passive set P (others fixed at their value in x).
Eigen::VectorXd solve_on_set(const Eigen::MatrixXd& g, const Eigen::VectorXd& b,
                             const std::vector<bool>& passive, const Eigen::VectorXd& x) {
  const Eigen::Index n = g.rows();
  std::vector<Eigen::Index> idx;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (passive[static_cast<std::size_t>(i)]) idx.push_back(i);
  }
  Eigen::VectorXd z = x;
  if (idx.empty()) return z;
  const auto m = static_cast<Eigen::Index>(idx.size());
  Eigen::MatrixXd gp(m, m);
  Eigen::VectorXd bp(m);
  for (Eigen::Index r = 0; r < m; ++r) {
    double rhs = b(idx[static_cast<std::size_t>(r)]);
    for (Eigen::Index c = 0; c < n; ++c) {
      if (!passive[static_cast<std::size_t>(c)])
        rhs -= g(idx[static_cast<std::size_t>(r)], c) * x(c);
    }
    bp(r) = rhs;
    for (Eigen::Index c = 0; c < m; ++c) {
      gp(r, c) = g(idx[static_cast<std::size_t>(r)], idx[static_cast<std::size_t>(c)]);
    }
  }
  const Eigen::VectorXd zp = gp.ldlt().solve(bp);
  for (Eigen::Index r = 0; r < m; ++r)
    z(idx[static_cast<std::size_t>(r)]) = zp(r);
  return z;
}

}  // namespace

BoundedLeastSquaresSolution solve_bounded_least_squares(const BoundedLeastSquaresProblem& problem,
                                                        const BoundedLeastSquaresOptions& options) {
  const Eigen::Index n = problem.gram.rows();
  if (problem.gram.cols() != n || problem.moment.size() != n ||
      problem.bounded.size() != static_cast<std::size_t>(n) || problem.lower.size() != n) {
    throw std::invalid_argument("solve_bounded_least_squares: sizes of G, b, bounds differ");
  }
  // Scale to unit diagonal: theta = s .* u.
  Eigen::VectorXd scale(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double d = problem.gram(i, i);
    scale(i) = d > 0.0 ? 1.0 / std::sqrt(d) : 1.0;
  }
  Eigen::MatrixXd g = scale.asDiagonal() * problem.gram * scale.asDiagonal();
  g.diagonal().array() += options.ridge;
  const Eigen::VectorXd b = scale.asDiagonal() * problem.moment;
  Eigen::VectorXd lower(n);
  for (Eigen::Index i = 0; i < n; ++i)
    lower(i) = problem.lower(i) / scale(i);

  const auto is_bounded = [&](Eigen::Index i) {
    return problem.bounded[static_cast<std::size_t>(i)];
  };
  // Start: bounded coefficients at their bound, free ones solved.
  std::vector<bool> passive(static_cast<std::size_t>(n));
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    passive[static_cast<std::size_t>(i)] = !is_bounded(i);
    if (is_bounded(i)) x(i) = lower(i);
  }
  x = solve_on_set(g, b, passive, x);

  const std::size_t max_iterations =
      options.max_iterations > 0 ? options.max_iterations : 3 * static_cast<std::size_t>(n) + 10;
  BoundedLeastSquaresSolution out;
  const double tolerance = 1e-12 * std::max(1.0, b.cwiseAbs().maxCoeff());
  for (; out.iterations < max_iterations; ++out.iterations) {
    // Most promising bound to release: largest descent direction b - G x.
    const Eigen::VectorXd w = b - g * x;
    Eigen::Index best = -1;
    double best_value = tolerance;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (is_bounded(i) && !passive[static_cast<std::size_t>(i)] && w(i) > best_value) {
        best = i;
        best_value = w(i);
      }
    }
    if (best < 0) {
      out.converged = true;
      break;
    }
    passive[static_cast<std::size_t>(best)] = true;
    // Inner loop: step towards the passive-set solution until it is feasible.
    for (Eigen::Index guard = 0; guard <= n; ++guard) {
      const Eigen::VectorXd z = solve_on_set(g, b, passive, x);
      double alpha = 1.0;
      Eigen::Index blocking = -1;
      for (Eigen::Index i = 0; i < n; ++i) {
        if (is_bounded(i) && passive[static_cast<std::size_t>(i)] && z(i) <= lower(i)) {
          const double denom = x(i) - z(i);
          const double a = denom > 0.0 ? (x(i) - lower(i)) / denom : 0.0;
          if (a < alpha) {
            alpha = a;
            blocking = i;
          }
        }
      }
      if (blocking < 0) {
        x = z;
        break;
      }
      x += alpha * (z - x);
      for (Eigen::Index i = 0; i < n; ++i) {
        if (is_bounded(i) && passive[static_cast<std::size_t>(i)] &&
            (i == blocking || x(i) <= lower(i) + 1e-15 * std::abs(lower(i)))) {
          passive[static_cast<std::size_t>(i)] = false;
          x(i) = lower(i);
        }
      }
    }
  }
  for (Eigen::Index i = 0; i < n; ++i) {
    if (is_bounded(i) && !passive[static_cast<std::size_t>(i)]) ++out.active_bounds;
  }
  out.theta = scale.asDiagonal() * x;
  out.residual_sum_of_squares =
      std::max(0.0, problem.output_energy - 2.0 * out.theta.dot(problem.moment) +
                        out.theta.dot(problem.gram * out.theta));
  return out;
}

GramAccumulator::GramAccumulator(Eigen::Index columns)
    : lower_(Eigen::MatrixXd::Zero(columns, columns)), moment_(Eigen::VectorXd::Zero(columns)) {}

void GramAccumulator::add(const Eigen::Ref<const Eigen::MatrixXd>& rows,
                          const Eigen::Ref<const Eigen::VectorXd>& y) {
  lower_.selfadjointView<Eigen::Lower>().rankUpdate(rows.transpose());
  moment_.noalias() += rows.transpose() * y;
  output_energy_ += y.squaredNorm();
  rows_ += static_cast<std::size_t>(rows.rows());
}

void GramAccumulator::add(const GramAccumulator& other) {
  assert(other.lower_.rows() == lower_.rows());
  lower_ += other.lower_;
  moment_ += other.moment_;
  output_energy_ += other.output_energy_;
  rows_ += other.rows_;
}

Eigen::MatrixXd GramAccumulator::gram() const {
  Eigen::MatrixXd full = lower_.selfadjointView<Eigen::Lower>();
  return full;
}

}  // namespace selfsense::identification
