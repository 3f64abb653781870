// Least squares with sign constraints on some coefficients, solved on the normal equations.
//
//   minimise 0.5 * theta' G theta - b' theta   subject to   theta_i >= lower_i  for i in C
//
// with G = A'A, b = A'y accumulated from the data (GramAccumulator). Lawson-Hanson active set
// method: deterministic, finite, no random restarts. Coefficients outside C are free. The
// problem is scaled by the diagonal of G first so that columns of very different units
// (V/m next to Pa) are treated alike, and a tiny ridge (relative `ridge`) keeps nearly
// collinear columns (neighbouring plays) solvable.
//
// Not real-time code: allocates.
#pragma once

#include <Eigen/Dense>
#include <cstddef>
#include <vector>

namespace selfsense::identification {

struct BoundedLeastSquaresProblem {
  Eigen::MatrixXd gram{};       // G = A'A (n x n, symmetric)
  Eigen::VectorXd moment{};     // b = A'y
  double output_energy{0.0};    // y'y, for the residual sum of squares
  std::vector<bool> bounded{};  // theta_i >= lower[i] when true
  Eigen::VectorXd lower{};      // lower bounds (used where bounded)
};

struct BoundedLeastSquaresOptions {
  double ridge{1e-10};            // relative to the scaled diagonal (which is 1)
  std::size_t max_iterations{0};  // 0: 3 * n
};

struct BoundedLeastSquaresSolution {
  Eigen::VectorXd theta{};
  double residual_sum_of_squares{0.0};  // ||A theta - y||^2
  std::size_t iterations{0};
  bool converged{false};
  std::size_t active_bounds{0};  // coefficients held at their bound
};

// Throws std::invalid_argument if the sizes disagree.
[[nodiscard]] BoundedLeastSquaresSolution solve_bounded_least_squares(
    const BoundedLeastSquaresProblem& problem, const BoundedLeastSquaresOptions& options = {});

// Accumulates G = A'A, b = A'y and y'y over blocks of rows, so a long recording never needs its
// whole regressor matrix in memory.
class GramAccumulator final {
 public:
  explicit GramAccumulator(Eigen::Index columns);
  // rows: block of regressor rows (k x n); y: the k matching outputs.
  void add(const Eigen::Ref<const Eigen::MatrixXd>& rows,
           const Eigen::Ref<const Eigen::VectorXd>& y);
  // Adds the rows another accumulator has seen (same column count, asserted).
  void add(const GramAccumulator& other);
  [[nodiscard]] Eigen::MatrixXd gram() const;  // full symmetric matrix
  [[nodiscard]] const Eigen::VectorXd& moment() const noexcept { return moment_; }
  [[nodiscard]] double output_energy() const noexcept { return output_energy_; }
  [[nodiscard]] std::size_t rows() const noexcept { return rows_; }

 private:
  Eigen::MatrixXd lower_{};  // lower triangle of G
  Eigen::VectorXd moment_{};
  double output_energy_{0.0};
  std::size_t rows_{0};
};

}  // namespace selfsense::identification
