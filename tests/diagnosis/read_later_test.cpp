// The delay undone offline (read_later.hpp): a sampled sine read back at fractional delays.
#include "selfsense/diagnosis/read_later.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace selfsense::diagnosis {
namespace {

// sin(w (k - late)): a sine sampled `late` samples late.
std::vector<double> sine(double w, double late, std::size_t n) {
  std::vector<double> x(n);
  for (std::size_t k = 0; k < n; ++k)
    x[k] = std::sin(w * (static_cast<double>(k) - late));
  return x;
}

// Largest error against the sine on time, away from the ends.
double worst(const std::vector<double>& v, double w, std::size_t margin) {
  double e = 0.0;
  for (std::size_t k = margin; k + margin < v.size(); ++k)
    e = std::max(e, std::abs(v[k] - std::sin(w * static_cast<double>(k))));
  return e;
}

TEST(ReadLater, UndoesASubSampleDelayToTheCubicInterpolatorsError) {
  // 0.3 rad per sample (a 480 Hz component at 10 kHz): the cubic read's error bound
  // |(t+1) t (t-1)(t-2)| / 24 w^4 is 1.6e-4 at t = 0.3; a linear read's t (1 - t) / 2 w^2 is
  // 9.5e-3.
  const double w = 0.3;
  for (const double late : {0.1, 0.3, 0.5, 0.8}) {
    const std::vector<double> back = read_later(sine(w, late, 400), late);
    EXPECT_LT(worst(back, w, 20), 2.0e-4) << "late " << late;
  }
}

TEST(ReadLater, ReadsWholeSamplesExactlyAndHoldsTheEnd) {
  const std::vector<double> x = sine(0.2, 3.0, 50);
  const std::vector<double> back = read_later(x, 3.0);
  for (std::size_t k = 0; k + 3 < x.size(); ++k)
    EXPECT_DOUBLE_EQ(back[k], x[k + 3]);
  for (std::size_t k = x.size() - 3; k < x.size(); ++k)
    EXPECT_DOUBLE_EQ(back[k], x.back());
}

TEST(ReadLater, ReadsLinearlyWhereANeighbourIsMissing) {
  const std::vector<double> x{0.0, 1.0, 4.0, 9.0, 16.0};
  const std::vector<double> back = read_later(x, 0.5);
  EXPECT_DOUBLE_EQ(back[0], 0.5);   // x[-1] missing: linear
  EXPECT_DOUBLE_EQ(back[1], 2.25);  // cubic through 0, 1, 4, 9: exact on k^2
  EXPECT_DOUBLE_EQ(back[3], 12.5);  // x[5] missing: linear
  EXPECT_DOUBLE_EQ(back[4], 16.0);  // beyond the end: held
}

TEST(ReadLater, LeavesTheRecordAsItIsWithoutADelay) {
  const std::vector<double> x{1.0, 2.0, 3.0};
  EXPECT_EQ(read_later(x, 0.0), x);
  EXPECT_EQ(read_later(x, -1.0), x);
  EXPECT_EQ(read_later(x, std::nan("")), x);
  EXPECT_TRUE(read_later({}, 0.5).empty());
}

}  // namespace
}  // namespace selfsense::diagnosis
