// The mode undone offline (mode_undone.hpp) against the correction stage's forward mode.
#include "selfsense/diagnosis/mode_undone.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

#include "selfsense/models/channel_correction.hpp"

namespace selfsense::diagnosis {
namespace {

// v through the stage's mode (its filters alone).
std::vector<double> through_mode(const std::vector<double>& v, double hz, double zeta, double ts) {
  models::ChannelCorrection c;
  c.dynamics_frequency_hz = hz;
  c.dynamics_damping = zeta;
  models::CorrectionStage stage(c, ts);
  std::vector<double> w(v.size());
  for (std::size_t k = 0; k < v.size(); ++k)
    w[k] = stage.filter(v[k]);
  return w;
}

double rms_between(const std::vector<double>& a, const std::vector<double>& b, std::size_t from,
                   std::size_t to) {
  double sum = 0.0;
  for (std::size_t k = from; k < to; ++k)
    sum += (a[k] - b[k]) * (a[k] - b[k]);
  return std::sqrt(sum / static_cast<double>(to - from));
}

TEST(ModeUndone, RecoversTheSignalBeforeAFastDampedMode) {
  // A 485 Hz mode with damping 0.27 at 1.1 kHz (the kind that looks like a lag) on sines up to
  // 0.11 fs and an edge: away from the ends the record before the mode comes back at least five
  // times closer than the mode had moved it.
  const double ts = 1.0 / 1100.0;
  // A step of 0.5 with a raised-cosine edge of 8 samples (the band of an amplifier's edge).
  const auto edge = [](std::size_t k) {
    if (k < 2000) return 0.0;
    if (k >= 2008) return 0.5;
    return 0.25 * (1.0 - std::cos(std::numbers::pi * static_cast<double>(k - 2000) / 8.0));
  };
  std::vector<double> v(4000);
  for (std::size_t k = 0; k < v.size(); ++k) {
    const double t = static_cast<double>(k) * ts;
    v[k] = std::sin(2.0 * std::numbers::pi * 3.0 * t) +
           0.3 * std::sin(2.0 * std::numbers::pi * 60.0 * t) +
           0.1 * std::sin(2.0 * std::numbers::pi * 120.0 * t) + edge(k);
  }
  const std::vector<double> w = through_mode(v, 485.0, 0.27, ts);
  const std::vector<double> back = mode_undone(w, 485.0, 0.27, ts);
  // Measured: the mode moves the record by 0.0046 RMS; undone, it is 0.00068 from v.
  const double moved = rms_between(w, v, 100, 3900);
  EXPECT_GT(moved, 0.004);
  EXPECT_LT(rms_between(back, v, 100, 3900), 0.2 * moved);
}

TEST(ModeUndone, DoesNotLiftTheSensorNoiseAboveAModeWellBelowNyquist) {
  // A 100 Hz mode (damping 0.05) at 1 kHz on a 3 Hz and a 20 Hz sine, white sensor noise of
  // 0.01 after the mode: the inverse lifts that noise by (f / f0)^2, 25 at Nyquist. Undone
  // within the mode's band, the record comes back closer than the noise itself.
  const double ts = 1e-3;
  std::vector<double> v(20000);
  for (std::size_t k = 0; k < v.size(); ++k) {
    const double t = static_cast<double>(k) * ts;
    v[k] = std::sin(2.0 * std::numbers::pi * 3.0 * t) +
           0.2 * std::sin(2.0 * std::numbers::pi * 20.0 * t);
  }
  std::vector<double> w = through_mode(v, 100.0, 0.05, ts);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (double& x : w)
    x += noise(rng);
  const std::vector<double> back = mode_undone(w, 100.0, 0.05, ts);
  // Measured: 0.0033 RMS from v (the noise alone is 0.01; undone without the low-pass, 0.51).
  EXPECT_LT(rms_between(back, v, 500, 19500), 0.005);
}

// Two modes in parallel and a direct path (the correction stage's whole dynamics block), on
// sines up to 0.03 fs and an edge: undone, the record before the block comes back at least five
// times closer than the block had moved it; a constant stays what it is.
TEST(ModeUndone, RecoversTheSignalBeforeTwoModesAndADirectPath) {
  const double ts = 1.0 / 5000.0;
  models::ChannelCorrection block;
  block.dynamics_frequency_hz = 300.0;
  block.dynamics_damping = 0.1;
  block.dynamics_direct = 0.1;
  block.dynamics2_frequency_hz = 700.0;
  block.dynamics2_damping = 0.15;
  block.dynamics2_share = 0.3;
  std::vector<double> v(20000);
  for (std::size_t k = 0; k < v.size(); ++k) {
    const double t = static_cast<double>(k) * ts;
    v[k] = std::sin(2.0 * std::numbers::pi * 3.0 * t) +
           0.3 * std::sin(2.0 * std::numbers::pi * 60.0 * t) +
           0.1 * std::sin(2.0 * std::numbers::pi * 150.0 * t) + (k >= 10000 ? 0.5 : 0.0);
  }
  models::CorrectionStage stage(block, ts);
  std::vector<double> w(v.size());
  for (std::size_t k = 0; k < v.size(); ++k)
    w[k] = stage.filter(v[k]);
  const std::vector<double> back = modes_undone(w, block, ts);
  const double moved = rms_between(w, v, 500, 19500);
  EXPECT_GT(moved, 0.01);
  EXPECT_LT(rms_between(back, v, 500, 19500), 0.2 * moved);
  for (const double x : modes_undone(std::vector<double>(200, 2.5), block, ts))
    EXPECT_NEAR(x, 2.5, 1e-9);
}

TEST(ModeUndone, KeepsAConstantAndRefusesAModeAboveNyquist) {
  const std::vector<double> w(50, 2.5);
  for (const double x : mode_undone(w, 40.0, 0.1, 1e-3))
    EXPECT_NEAR(x, 2.5, 1e-9);
  EXPECT_THROW(static_cast<void>(mode_undone(w, 600.0, 0.3, 1e-3)), std::invalid_argument);
  EXPECT_TRUE(mode_undone({}, 40.0, 0.1, 1e-3).empty());
}

}  // namespace
}  // namespace selfsense::diagnosis
