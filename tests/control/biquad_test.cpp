// Biquad designs: frequency response measured by simulation against the analytic H(e^jwT).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

#include "control/simulated_plants.hpp"
#include "selfsense/control/filter_chain.hpp"
#include "selfsense/control/filter_design.hpp"

namespace selfsense::control {
namespace {

constexpr double kTs = 1.0 / 20000.0;  // 20 kHz loop

double db(double gain) {
  return 20.0 * std::log10(gain);
}

// Steady-state gain of `filter` for a unit sine at f [Hz]: 2 s of drive, fitted over the last
// second (a whole number of periods for the frequencies used here).
template <typename Filter>
double simulated_gain(Filter filter, double frequency) {
  const std::size_t n = 40000;
  const std::size_t first = n / 2;
  std::vector<double> tail;
  tail.reserve(n - first);
  for (std::size_t k = 0; k < n; ++k) {
    const double x = std::sin(2.0 * std::numbers::pi * frequency * kTs * static_cast<double>(k));
    const double y = filter.step(x);
    if (k >= first) tail.push_back(y);
  }
  return test::amplitude_at(tail, frequency, kTs, first);
}

TEST(Biquad, NotchDepthAtItsFrequencyAndUnityFarAway) {
  const double f0 = 500.0;
  const BiquadCoefficients c = notch({.frequency = f0, .quality = 4.0, .depth_db = 30.0}, kTs);
  // Pre-warping puts the analog depth exactly at f0.
  EXPECT_NEAR(db(std::abs(c.response(f0, kTs))), -30.0, 1e-9);
  EXPECT_NEAR(db(simulated_gain(Biquad(c), f0)), -30.0, 1.0);
  EXPECT_NEAR(c.dc_gain(), 1.0, 1e-12);
  EXPECT_NEAR(std::abs(c.response(10000.0, kTs)), 1.0, 1e-9);  // Nyquist
  for (const double f : {20.0, 50.0, 5000.0, 8000.0}) {
    EXPECT_NEAR(db(simulated_gain(Biquad(c), f)), 0.0, 0.1) << f << " Hz";
  }
}

TEST(Biquad, SimulatedResponseMatchesTheAnalyticOneAtSeveralFrequencies) {
  const std::array<BiquadCoefficients, 5> designs = {
      notch({.frequency = 1000.0, .bandwidth = 200.0, .depth_db = 20.0}, kTs),
      low_pass(SecondOrderDesign{.frequency = 2000.0}, kTs),
      high_pass(SecondOrderDesign{.frequency = 200.0, .quality = 0.9}, kTs),
      low_pass(FirstOrderDesign{.frequency = 800.0}, kTs),
      high_pass(FirstOrderDesign{.frequency = 300.0}, kTs)};
  for (const BiquadCoefficients& c : designs) {
    for (const double f : {50.0, 200.0, 800.0, 1000.0, 2000.0, 5000.0}) {
      const double analytic = std::abs(c.response(f, kTs));
      EXPECT_NEAR(simulated_gain(Biquad(c), f), analytic, 1e-6 + 1e-4 * analytic)
          << "b0 = " << c.b0 << " at " << f << " Hz";
    }
  }
}

TEST(Biquad, CornerGainsOfTheLowAndHighPassDesigns) {
  const double f0 = 1500.0;
  const double corner = 1.0 / std::numbers::sqrt2;  // Butterworth and first order: -3 dB
  EXPECT_NEAR(std::abs(low_pass(SecondOrderDesign{.frequency = f0}, kTs).response(f0, kTs)), corner,
              1e-12);
  EXPECT_NEAR(std::abs(high_pass(SecondOrderDesign{.frequency = f0}, kTs).response(f0, kTs)),
              corner, 1e-12);
  EXPECT_NEAR(std::abs(low_pass(FirstOrderDesign{.frequency = f0}, kTs).response(f0, kTs)), corner,
              1e-12);
  // Given Q: |H(f0)| = Q for the second-order low-pass.
  EXPECT_NEAR(std::abs(low_pass(SecondOrderDesign{f0, 3.0}, kTs).response(f0, kTs)), 3.0, 1e-9);
  EXPECT_NEAR(low_pass(SecondOrderDesign{.frequency = f0}, kTs).dc_gain(), 1.0, 1e-12);
  EXPECT_NEAR(high_pass(SecondOrderDesign{.frequency = f0}, kTs).dc_gain(), 0.0, 1e-12);
  EXPECT_NEAR(std::abs(high_pass(SecondOrderDesign{.frequency = f0}, kTs).response(9999.0, kTs)),
              1.0, 1e-6);
}

TEST(Biquad, ResetSettlesAtTheDcGain) {
  Biquad lp(low_pass(SecondOrderDesign{.frequency = 300.0}, kTs));
  lp.reset(2.5);
  for (int k = 0; k < 5; ++k)
    EXPECT_NEAR(lp.step(2.5), 2.5, 1e-12);
}

TEST(FilterChain, TwoNotchesAndALowPassMultiplyTheirResponses) {
  const std::array<BiquadCoefficients, 3> sections = {
      notch({.frequency = 700.0, .quality = 5.0, .depth_db = 40.0}, kTs),
      notch({.frequency = 2100.0, .quality = 5.0, .depth_db = 40.0}, kTs),
      low_pass(SecondOrderDesign{.frequency = 4000.0}, kTs)};
  const FilterChain chain(sections);
  ASSERT_EQ(chain.size(), 3U);
  EXPECT_EQ(chain.state_size(), 6U);
  for (const double f : {100.0, 700.0, 2100.0, 4000.0}) {
    std::complex<double> product{1.0, 0.0};
    for (const BiquadCoefficients& c : sections)
      product *= c.response(f, kTs);
    EXPECT_NEAR(std::abs(chain.response(f, kTs)), std::abs(product), 1e-12);
    EXPECT_NEAR(simulated_gain(chain, f), std::abs(product), 1e-6 + 1e-4 * std::abs(product))
        << f << " Hz";
  }
  EXPECT_NEAR(db(std::abs(chain.response(700.0, kTs))), -40.0, 0.5);
}

TEST(FilterChain, EmptyChainPassesThroughAndResetIsSteady) {
  FilterChain empty;
  EXPECT_EQ(empty.step(3.25), 3.25);
  const std::array<BiquadCoefficients, 2> sections = {
      low_pass(FirstOrderDesign{.frequency = 100.0}, kTs),
      notch({.frequency = 50.0, .quality = 1.0, .depth_db = 6.0}, kTs)};
  FilterChain chain(sections);
  chain.reset(-1.5);
  EXPECT_NEAR(chain.step(-1.5), -1.5, 1e-12);
}

TEST(FilterChain, SetSectionSwapsStableCoefficientsOnly) {
  const std::array<BiquadCoefficients, 1> sections = {
      low_pass(SecondOrderDesign{.frequency = 100.0}, kTs)};
  FilterChain chain(sections);
  const BiquadCoefficients replacement = notch({.frequency = 300.0, .quality = 2.0}, kTs);
  EXPECT_TRUE(chain.set_section(0, replacement));
  EXPECT_EQ(chain.section(0).b0, replacement.b0);
  EXPECT_FALSE(chain.set_section(1, replacement));
  BiquadCoefficients unstable = replacement;
  unstable.a2 = 1.5;
  EXPECT_FALSE(chain.set_section(0, unstable));
  EXPECT_EQ(chain.section(0).a2, replacement.a2);
}

// A reload's new chain: a section that stays keeps its state, a changed or added one starts
// settled (no bump on a constant input), an unstable one changes nothing.
TEST(FilterChain, AssignKeepsStateSettlesAddedSectionsAndRefusesUnstableOnes) {
  const std::array<BiquadCoefficients, 1> one{notch({500.0, 2.0, 0.0, 20.0}, kTs)};
  FilterChain chain(one);
  chain.reset(3.0);
  for (int i = 0; i < 10; ++i)
    EXPECT_NEAR(chain.step(3.0), 3.0, 1e-12);
  const std::array<BiquadCoefficients, 3> three{notch({600.0, 2.0, 0.0, 20.0}, kTs),
                                                low_pass(SecondOrderDesign{2000.0, 0.7071}, kTs),
                                                low_pass(FirstOrderDesign{3000.0}, kTs)};
  // A kept section keeps its state: mid-transient, the output goes on as without the assign.
  FilterChain twin(one);
  chain.reset(0.0);
  twin.reset(0.0);
  for (int i = 0; i < 5; ++i)
    EXPECT_EQ(chain.step(1.0), twin.step(1.0));
  ASSERT_TRUE(chain.assign(one, 123.0));
  for (int i = 0; i < 5; ++i)
    EXPECT_EQ(chain.step(1.0), twin.step(1.0));
  chain.reset(3.0);
  ASSERT_TRUE(chain.assign(three, 3.0));
  EXPECT_EQ(chain.size(), 3U);
  EXPECT_EQ(chain.section(1).b0, three[1].b0);
  for (int i = 0; i < 10; ++i)
    EXPECT_NEAR(chain.step(3.0), 3.0, 1e-9);  // steady, no transient from the added sections

  BiquadCoefficients unstable = three[1];
  unstable.a2 = 1.5;
  const std::array<BiquadCoefficients, 2> bad{one[0], unstable};
  EXPECT_FALSE(chain.assign(bad, 3.0));
  EXPECT_EQ(chain.size(), 3U);
  EXPECT_EQ(chain.section(0).b0, three[0].b0);
  const std::array<BiquadCoefficients, 5> too_many{};
  EXPECT_FALSE(chain.assign(too_many, 3.0));
  EXPECT_TRUE(chain.assign({}, 0.0));
  EXPECT_EQ(chain.step(7.0), 7.0);
}

}  // namespace
}  // namespace selfsense::control
