// The least squares of a channel correction: planted coefficients found, and the held-out refits
// (cross-validation by folds) equal to fits without each fold.
#include "selfsense/identification/correction_fit.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

namespace selfsense::identification {
namespace {

constexpr double kTs = 1e-3;

struct Bench {
  std::vector<double> x, y, recorded;
  CorrectionSignals signals() const {
    CorrectionSignals s;
    s.y = y;
    s.recorded = recorded;
    s.drive = x;
    s.sample_time = kTs;
    return s;
  }
};

// A drive of holds and sines; the model's output 2 x; the recording 1.05 times it, 0.02 higher
// and with a small loop (a play of the drive), so the hysteresis terms have something to fit.
Bench bench() {
  Bench b;
  double play = 0.0;
  for (int k = 0; k < 6000; ++k) {
    const double t = k * kTs;
    const int level = k / 500;  // a hold every 0.5 s, then a sine
    const double x = (k < 3000) ? 0.2 * level : std::sin(8.17 * t);
    play = std::clamp(play, x - 0.1, x + 0.1);
    b.x.push_back(x);
    b.y.push_back(2.0 * x);
    b.recorded.push_back(1.05 * 2.0 * x + 0.02 + 0.05 * play);
  }
  return b;
}

TEST(CorrectionFit, FindsAPlantedGainAndOffset) {
  Bench b = bench();
  for (std::size_t k = 0; k < b.x.size(); ++k)
    b.recorded[k] = 1.05 * b.y[k] + 0.02;
  const std::vector<CorrectionTerm> terms{CorrectionTerm::kOffset};
  const CorrectionFit fit =
      fit_correction(b.signals(), terms, {}, std::vector<bool>(b.x.size(), true));
  EXPECT_NEAR(fit.correction.gain, 0.05, 1e-12);
  EXPECT_NEAR(fit.correction.offset, 0.02, 1e-12);
  EXPECT_LT(fit.fit_sse, 1e-20);
}

// A coupling d (1 + k T) under a preload T0: a model identified there has the coupling
// d (1 + k T0) in its response r and leaves k (T - T0) r, whatever T0 is. The stress term reaches
// it with the gain (on y = r + s T) and the stress's own column: found exactly.
TEST(CorrectionFit, StressGainIsFoundAboutTheRecordingsPreload) {
  Bench b = bench();
  constexpr double kCompliance = 2e-8;  // s [channel unit / Pa]
  constexpr double kPerPa = 3e-8;       // k
  constexpr double kPreload = -3e6;     // T0 [Pa]
  std::vector<double> stress;
  std::vector<double> response;
  for (std::size_t k = 0; k < b.x.size(); ++k) {
    const double t = static_cast<double>(k) * kTs;
    const double r = b.y[k];
    stress.push_back(kPreload + 1e6 * std::sin(1.3 * t) + 2e5 * std::sin(37.0 * t));
    response.push_back(r);
    b.y[k] = r + kCompliance * stress[k];
    b.recorded[k] = r * (1.0 + kPerPa * (stress[k] - kPreload)) + kCompliance * stress[k];
  }
  CorrectionSignals s = b.signals();
  s.stress = stress;
  s.response = response;
  const std::vector<CorrectionTerm> terms{CorrectionTerm::kStress, CorrectionTerm::kOffset};
  const CorrectionFit fit = fit_correction(s, terms, {}, std::vector<bool>(b.x.size(), true));
  EXPECT_NEAR(fit.correction.stress_gain_per_pa, kPerPa, 1e-6 * kPerPa);
  EXPECT_NEAR(fit.correction.gain, -kPerPa * kPreload, 1e-6);
  EXPECT_NEAR(fit.correction.stress_linear_per_pa, kPerPa * kPreload * kCompliance,
              1e-6 * kPerPa * 3e6 * kCompliance);
  double worst = 0.0;
  for (std::size_t k = 0; k < b.x.size(); ++k)
    worst = std::max(worst, std::abs(fit.output[k] - b.recorded[k]));
  EXPECT_LT(worst, 1e-9);  // of a response up to 2.4
}

// Two modes in parallel and a share passing neither (models/channel_correction.hpp), planted on
// steps of a model output: the search finds both frequencies (the second with the first fixed,
// then both refined) and the shares, where one mode alone leaves far more.
TEST(CorrectionFit, FindsTwoPlantedModesAndTheDirectShare) {
  constexpr double kFastTs = 1e-4;
  models::ChannelCorrection planted;
  planted.dynamics_frequency_hz = 300.0;
  planted.dynamics_damping = 0.05;
  planted.dynamics_direct = 0.1;
  planted.dynamics2_frequency_hz = 900.0;
  planted.dynamics2_damping = 0.1;
  planted.dynamics2_share = 0.3;
  std::vector<double> y;
  std::uint64_t state = 12345;
  double level = 0.0;
  for (int k = 0; k < 20000; ++k) {
    if (k % 200 == 0) {  // a step every 20 ms to a level drawn in [-1, 1]
      state = state * 6364136223846793005ULL + 1442695040888963407ULL;
      level = static_cast<double>(state >> 11U) * 0x1.0p-52 - 1.0;
    }
    y.push_back(level);
  }
  CorrectionSignals s;
  s.y = y;
  s.drive = y;
  s.sample_time = kFastTs;
  const std::vector<double> recorded = apply_correction(s, planted);
  s.recorded = recorded;
  const std::vector<bool> rows(y.size(), true);
  const std::vector<CorrectionTerm> two{CorrectionTerm::kDynamics, CorrectionTerm::kSecondMode};
  const CorrectionFit fit = fit_correction(s, two, {}, rows);
  const models::ChannelCorrection& c = fit.correction;
  EXPECT_NEAR(c.dynamics_frequency_hz, 300.0, 3.0);
  EXPECT_NEAR(c.dynamics_damping, 0.05, 0.005);
  EXPECT_NEAR(c.dynamics2_frequency_hz, 900.0, 9.0);
  EXPECT_NEAR(c.dynamics2_damping, 0.1, 0.01);
  EXPECT_NEAR(c.dynamics_direct, 0.1, 0.01);
  EXPECT_NEAR(c.dynamics2_share, 0.3, 0.01);
  const std::vector<CorrectionTerm> one{CorrectionTerm::kDynamics};
  const CorrectionFit single = fit_correction(s, one, {}, rows);
  EXPECT_LT(fit.fit_sse, 1e-3 * single.fit_sse);
  // Held out with the modes chosen: the shares are refitted per fold, the modes kept.
  std::vector<int> fold(y.size(), -1);
  for (std::size_t k = 0; k < 10000; ++k)
    fold[k] = 0;
  const std::vector<std::vector<double>> out = held_out_outputs(s, two, c, rows, fold, 1);
  std::vector<bool> without(y.size(), true);
  for (std::size_t k = 0; k < 10000; ++k)
    without[k] = false;
  const CorrectionFit refit = fit_correction(s, two, c, without);
  double largest = 0.0;
  for (std::size_t k = 0; k < y.size(); ++k)
    largest = std::max(largest, std::abs(out[0][k] - refit.output[k]));
  EXPECT_LT(largest, 1e-9);
}

TEST(CorrectionFit, HeldOutOutputsEqualFitsWithoutEachFold) {
  const Bench b = bench();
  const std::size_t n = b.x.size();
  const std::vector<CorrectionTerm> terms{CorrectionTerm::kHysteresis, CorrectionTerm::kOffset};
  std::vector<bool> rows(n, true);
  rows[17] = false;  // a sample no fit may use
  std::vector<int> fold(n, -1);
  for (std::size_t k = 0; k < 3000; ++k)
    fold[k] = static_cast<int>((k / 500) % 3);  // six holds in three folds
  const std::vector<std::vector<double>> out =
      held_out_outputs(b.signals(), terms, {}, rows, fold, 3);
  ASSERT_EQ(out.size(), 3U);
  for (int f = 0; f < 3; ++f) {
    std::vector<bool> without = rows;
    for (std::size_t k = 0; k < n; ++k)
      without[k] = without[k] && fold[k] != f;
    const CorrectionFit fit = fit_correction(b.signals(), terms, {}, without);
    ASSERT_EQ(out[static_cast<std::size_t>(f)].size(), n);
    double largest = 0.0;
    for (std::size_t k = 0; k < n; ++k)
      largest = std::max(largest, std::abs(out[static_cast<std::size_t>(f)][k] - fit.output[k]));
    EXPECT_LT(largest, 1e-9) << "fold " << f;
  }
}

TEST(CorrectionFit, HeldOutOutputsNeedTheFiltersChosen) {
  const Bench b = bench();
  const std::vector<CorrectionTerm> terms{CorrectionTerm::kLeakage, CorrectionTerm::kOffset};
  const std::vector<int> fold(b.x.size(), 0);
  EXPECT_THROW(static_cast<void>(held_out_outputs(b.signals(), terms, {},
                                                  std::vector<bool>(b.x.size(), true), fold, 1)),
               std::invalid_argument);
  models::ChannelCorrection chosen;
  chosen.leakage_tau_s = 50.0;
  std::vector<int> two(b.x.size(), -1);
  for (std::size_t k = 0; k < 1000; ++k)
    two[k] = 0;
  EXPECT_EQ(
      held_out_outputs(b.signals(), terms, chosen, std::vector<bool>(b.x.size(), true), two, 1)
          .size(),
      1U);
}

}  // namespace
}  // namespace selfsense::identification
