// The play count that `identify --structure stress-hysteresis` chooses on the fitting data
// (transducer_fit.hpp): when the first three quarters, where the candidates are fitted, hold
// the stress constant, there is nothing to choose on and the given count is used.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "selfsense/identification/transducer_fit.hpp"

namespace selfsense::identification {
namespace {

TEST(StressPlaysChoice, FallsBackToTheGivenCountWhenTheFittedPartHasNoStressChange) {
  constexpr std::size_t kSamples = 4000;
  std::vector<double> e;
  std::vector<double> t;
  std::vector<double> d;
  for (std::size_t k = 0; k < kSamples; ++k) {
    const double time = static_cast<double>(k) * 1e-3;
    e.push_back(1e6 + 0.9e6 * std::sin(2 * std::numbers::pi * time));
    t.push_back(k < kSamples * 3 / 4 ? -1e7 : -1e7 - 2e4 * static_cast<double>(k % 1000));
    d.push_back(1e-8 * e.back() + 3e-10 * t.back());
  }
  IdentificationOptions o = defaults_for(models::Structure::kStressHysteresis);
  ASSERT_TRUE(o.choose_plays);
  o.plays = 5;
  const models::TransducerModel m =
      identify({e, d, t, {}, 1e-3}, models::Structure::kStressHysteresis, o);
  ASSERT_TRUE(m.vectorial.has_value());
  EXPECT_EQ(m.vectorial->basis.thresholds.size(), 6U);  // the linear term and 5 plays
}

}  // namespace
}  // namespace selfsense::identification
