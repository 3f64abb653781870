#include "selfsense/operators/regressor_stream.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <span>
#include <vector>

#include "support/random_walk.hpp"

namespace selfsense::operators {
namespace {

// Plays of thresholds 0, 0.25, ..., 1.75, lags at two rates, hinges on two plays.
OperatorBasis basis_with_lags_on(std::vector<std::size_t> creep_rows) {
  OperatorBasis b;
  for (int i = 0; i < 8; ++i)
    b.thresholds.push_back(0.25 * i);
  b.creep_rows = std::move(creep_rows);
  b.eigenvalues = {50.0, 2.0};
  for (const double l : b.eigenvalues)
    b.gains.push_back(-std::expm1(-l * 1e-3));
  b.hinge_rows = {2, 5};
  b.hinge_levels = {0.1, -0.3};
  return b;
}

// A walk on a grid of 0.05 (plateaus, equal neighbours) with slow monotone stretches between.
std::vector<double> input() {
  std::vector<double> x = test::random_walk(4000, -3.0, 3.0, 0.15, 11);
  for (double& v : x)
    v = std::round(v / 0.05) * 0.05;
  for (std::size_t k = 0; k < 300; ++k)
    x.push_back(x.back() + 0.01);  // one long rise
  return x;
}

// Rows from next() at every `step`-th sample, skip() over the samples between, against next()
// at every sample: the same doubles, bit for bit.
void expect_same_rows(const OperatorBasis& basis, std::span<const double> history,
                      std::size_t step) {
  const std::vector<double> x = input();
  RegressorStream every(basis, history);
  RegressorStream skipping(basis, history);
  std::size_t compared = 0;
  for (std::size_t k = 0; k < x.size(); k += step) {
    const std::size_t last = std::min(k + step, x.size()) - 1;
    for (std::size_t j = k; j < last; ++j)
      static_cast<void>(every.next(x[j]));
    skipping.skip(std::span<const double>(x).subspan(k, last - k));
    const std::span<const double> want = every.next(x[last]);
    const std::span<const double> got = skipping.next(x[last]);
    ASSERT_EQ(want.size(), got.size());
    for (std::size_t c = 0; c < want.size(); ++c)
      ASSERT_EQ(want[c], got[c]) << "sample " << last << " column " << c << " step " << step;
    ++compared;
  }
  EXPECT_GT(compared, x.size() / (step + 1));
}

TEST(RegressorStream, SkippingWhereTheLagsFollowTheInputLeavesTheSameRows) {
  const OperatorBasis basis = basis_with_lags_on({0});
  for (const std::size_t step : {1UL, 2UL, 5UL, 40UL})
    expect_same_rows(basis, std::vector<double>{-3.0, 3.0, -0.5, 0.0}, step);
}

TEST(RegressorStream, SkippingWhereTheLagsFollowPlaysLeavesTheSameRows) {
  const OperatorBasis basis = basis_with_lags_on({0, 3, 6});
  for (const std::size_t step : {2UL, 7UL})
    expect_same_rows(basis, std::vector<double>{-3.0, 3.0, -0.5, 0.0}, step);
}

TEST(RegressorStream, SkippingFromNoHistoryAndAfterARestoreLeavesTheSameRows) {
  const OperatorBasis basis = basis_with_lags_on({0});
  expect_same_rows(basis, {}, 9);

  const std::vector<double> x = input();
  RegressorStream every(basis, std::vector<double>{0.0});
  for (std::size_t k = 0; k < 100; ++k)
    static_cast<void>(every.next(x[k]));
  std::vector<double> state(every.state_size());
  every.save_state(state);
  RegressorStream restored(basis, std::vector<double>{2.0});
  restored.restore_state(state);
  restored.skip(std::span<const double>(x).subspan(100, 600));
  for (std::size_t k = 100; k < 700; ++k)
    static_cast<void>(every.next(x[k]));
  const std::span<const double> want = every.next(x[700]);
  const std::span<const double> got = restored.next(x[700]);
  for (std::size_t c = 0; c < want.size(); ++c)
    ASSERT_EQ(want[c], got[c]) << "column " << c;
}

}  // namespace
}  // namespace selfsense::operators
