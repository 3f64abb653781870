#include "selfsense/identification/nnls.hpp"

#include <gtest/gtest.h>

#include <random>

namespace selfsense::identification {
namespace {

BoundedLeastSquaresProblem problem_from(const Eigen::MatrixXd& a, const Eigen::VectorXd& y,
                                        std::vector<bool> bounded, Eigen::VectorXd lower) {
  GramAccumulator acc(a.cols());
  acc.add(a.topRows(a.rows() / 2), y.head(a.rows() / 2));
  acc.add(a.bottomRows(a.rows() - a.rows() / 2), y.tail(a.rows() - a.rows() / 2));
  return {acc.gram(), acc.moment(), acc.output_energy(), std::move(bounded), std::move(lower)};
}

TEST(BoundedLeastSquares, UnconstrainedEqualsOrdinaryLeastSquares) {
  std::mt19937_64 rng(1);
  std::normal_distribution<double> n01;
  Eigen::MatrixXd a(200, 5);
  for (Eigen::Index i = 0; i < a.size(); ++i)
    a.data()[i] = n01(rng);
  Eigen::VectorXd y(200);
  for (Eigen::Index i = 0; i < y.size(); ++i)
    y(i) = n01(rng);
  const auto sol = solve_bounded_least_squares(
      problem_from(a, y, std::vector<bool>(5, false), Eigen::VectorXd::Zero(5)), {0.0, 0});
  const Eigen::VectorXd ols = a.colPivHouseholderQr().solve(y);
  EXPECT_LT((sol.theta - ols).norm(), 1e-10);
  EXPECT_NEAR(sol.residual_sum_of_squares, (a * ols - y).squaredNorm(), 1e-9);
  EXPECT_TRUE(sol.converged);
}

TEST(BoundedLeastSquares, ActiveBoundsAreHeldAndKktHolds) {
  // y = A [1, -2, 0.5, -0.1] + noise; coefficients 1 and 3 bounded below by 0 and 0.
  std::mt19937_64 rng(2);
  std::normal_distribution<double> n01;
  Eigen::MatrixXd a(500, 4);
  for (Eigen::Index i = 0; i < a.size(); ++i)
    a.data()[i] = n01(rng);
  Eigen::VectorXd truth(4);
  truth << 1.0, -2.0, 0.5, -0.1;
  Eigen::VectorXd y = a * truth;
  for (Eigen::Index i = 0; i < y.size(); ++i)
    y(i) += 0.01 * n01(rng);
  const std::vector<bool> bounded{false, true, false, true};
  const auto sol =
      solve_bounded_least_squares(problem_from(a, y, bounded, Eigen::VectorXd::Zero(4)));
  EXPECT_TRUE(sol.converged);
  EXPECT_NEAR(sol.theta(1), 0.0, 1e-12);
  EXPECT_NEAR(sol.theta(3), 0.0, 1e-12);
  EXPECT_EQ(sol.active_bounds, 2U);
  // KKT: gradient zero on free coordinates, pointing into the bound on active ones.
  const Eigen::VectorXd grad = a.transpose() * (a * sol.theta - y);
  EXPECT_NEAR(grad(0), 0.0, 1e-6);
  EXPECT_NEAR(grad(2), 0.0, 1e-6);
  EXPECT_GT(grad(1), 0.0);
  EXPECT_GT(grad(3), 0.0);
}

TEST(BoundedLeastSquares, PositiveLowerBound) {
  Eigen::MatrixXd a = Eigen::MatrixXd::Identity(3, 3);
  Eigen::VectorXd y(3);
  y << 0.5, -1.0, 2.0;
  Eigen::VectorXd lower(3);
  lower << 1.0, 0.1, 0.0;
  const auto sol = solve_bounded_least_squares(problem_from(a, y, {true, true, true}, lower));
  EXPECT_NEAR(sol.theta(0), 1.0, 1e-12);
  EXPECT_NEAR(sol.theta(1), 0.1, 1e-12);
  EXPECT_NEAR(sol.theta(2), 2.0, 1e-9);
}

TEST(BoundedLeastSquares, RejectsMismatchedSizes) {
  BoundedLeastSquaresProblem p{Eigen::MatrixXd::Identity(2, 2),
                               Eigen::VectorXd::Zero(3),
                               0.0,
                               {false, false},
                               Eigen::VectorXd::Zero(2)};
  EXPECT_THROW(static_cast<void>(solve_bounded_least_squares(p)), std::invalid_argument);
}

}  // namespace
}  // namespace selfsense::identification
