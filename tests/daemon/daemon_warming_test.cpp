// The self-sensed S and T of the real selfsensed while the simulated stack warms 25 -> 45 degC,
// with and without the online adaptation (docs/daemon.md, "Adaptation": the figures, asserted at
// about 1.3x of the measured ones). Three runs of about 37 s in real time.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "daemon/recording_support.hpp"
#include "daemon/running_daemon.hpp"
#include "daemon/warming_support.hpp"
#include "selfsense/io/recording.hpp"

namespace selfsense::daemon {
namespace {

using testing::play_sine;
using testing::RunningDaemon;
using testing::warming_config;

// Measured (docs/daemon.md, "Adaptation"); asserted at about 1.3x. The adapted figures since the
// mount's prediction follows the drift (2026-11-27, four runs).
constexpr double kMeasuredAdaptedS = 0.00758;      // S_hat nrmse, whole run (0.744-0.758 %)
constexpr double kMeasuredAdaptedT = 0.0419;       // T_hat (4.10-4.19 %)
constexpr double kMeasuredAdaptedLastS = 0.00956;  // last fifth (0.879-0.956 %)
constexpr double kMeasuredAdaptedLastT = 0.0559;   // (5.26-5.59 %)
constexpr double kMeasuredPlainS = 0.0402;         // without adaptation (4.02-4.14 %)
constexpr double kMeasuredPlainT = 0.2125;         // (21.25-21.93 %)
constexpr double kMeasuredTemperatureError = 2.5;  // [K] at the end (2.21-2.44 K)
// With the temperature channel (adaptation.use_temperature), two runs on 2026-11-27.
constexpr double kMeasuredChannelS = 0.00254;      // 0.248-0.254 %
constexpr double kMeasuredChannelT = 0.01575;      // 1.528-1.575 %
constexpr double kMeasuredChannelLastS = 0.00364;  // last fifth 0.356-0.364 %
constexpr double kMeasuredChannelLastT = 0.02403;  // 2.309-2.403 %

struct Errors {
  double s_nrmse{0.0};       // RMS(S_hat - S) / range(S)
  double t_nrmse{0.0};       // RMS(T_hat - T) / range(T)
  double s_last_nrmse{0.0};  // over the last fifth (the hottest)
  double t_last_nrmse{0.0};
};

double nrmse(const std::vector<double>& est, const std::vector<double>& ref, std::size_t from,
             std::size_t to) {
  double sum = 0.0;
  double lo = ref[from];
  double hi = ref[from];
  for (std::size_t i = from; i < to; ++i) {
    sum += (est[i] - ref[i]) * (est[i] - ref[i]);
    lo = std::min(lo, ref[i]);
    hi = std::max(hi, ref[i]);
  }
  return std::sqrt(sum / static_cast<double>(to - from)) / (hi - lo);
}

// The armed rows of every recording in dir, after the first second (the arm's transient).
Errors errors_of(const std::filesystem::path& dir) {
  std::vector<double> s;
  std::vector<double> t;
  std::vector<double> s_hat;
  std::vector<double> t_hat;
  for (const auto& file : testing::csv_files(dir, "selfsensed")) {
    const io::Recording r =
        io::read_recording_csv(file, {{"t", "S", "T", "S_hat", "T_hat", "state"}});
    const auto time = r.column("t");
    const auto state = r.column("state");
    const auto cs = r.column("S");
    const auto ct = r.column("T");
    const auto cs_hat = r.column("S_hat");
    const auto ct_hat = r.column("T_hat");
    for (std::size_t i = 0; i < time.size(); ++i) {
      if (state[i] != 2.0) continue;  // armed
      s.push_back(cs[i]);
      t.push_back(ct[i]);
      s_hat.push_back(cs_hat[i]);
      t_hat.push_back(ct_hat[i]);
    }
  }
  const std::size_t skip = static_cast<std::size_t>(testing::kProcessTestRate);
  EXPECT_GT(s.size(), 20 * skip);
  if (s.size() <= 20 * skip) return {};
  const std::size_t n = s.size();
  const std::size_t last = n - (n - skip) / 5;
  return {nrmse(s_hat, s, skip, n), nrmse(t_hat, t, skip, n), nrmse(s_hat, s, last, n),
          nrmse(t_hat, t, last, n)};
}

// One run: the stack warms 25 -> 45 degC over 30 s while a 2 Hz sine plays in position mode,
// then 6 s more at 45 degC, recorded; the errors and the final equivalent temperature. With
// use_temperature the simulated driver's temperature channel replaces the estimate
// (adaptation.use_temperature).
// measured_degc: the driver's temperature as `status` shows it at the end (estimate.temp).
Errors warming_run(bool adapt, double* equivalent_degc, bool use_temperature = false,
                   double* measured_degc = nullptr) {
  const testing::ScratchDir dir(use_temperature ? "daemon-warming-temperature"
                                : adapt         ? "daemon-warming-adapted"
                                                : "daemon-warming-plain");
  static_cast<void>(testing::copy_shipped_model(dir.path()));
  const std::filesystem::path config = dir.path() / "selfsensed.yaml";
  std::vector<std::pair<std::string, std::string>> extra;
  if (use_temperature) extra.emplace_back("use_temperature: false", "use_temperature: true");
  testing::write_text(config, warming_config(dir.path(), adapt, 30.0, extra));
  {
    RunningDaemon daemon(config, dir.path() / "control.sock", dir.path() / "selfsensed.log");
    play_sine(daemon);
    const nlohmann::json rec = daemon.request(R"({"request": "record", "action": "start"})");
    EXPECT_TRUE(rec.value("ok", false)) << rec.dump();
    std::this_thread::sleep_for(std::chrono::seconds(36));
    const nlohmann::json s = daemon.status();
    EXPECT_EQ(s["state"], "armed") << s.dump();
    if (adapt) *equivalent_degc = s["adaptation"]["temperature_degc"].get<double>();
    if (measured_degc != nullptr) *measured_degc = s["estimate"].value("temp", -273.15);
    EXPECT_TRUE(daemon.request(R"({"request": "record", "action": "stop"})").value("ok", false));
    EXPECT_EQ(daemon.terminate(), 0);
  }
  return errors_of(dir.path() / "recordings");
}

TEST(DaemonAdaptation, TheSelfSensedStrainHoldsWhileTheStackWarms) {
  double equivalent = 0.0;
  const Errors plain = warming_run(false, &equivalent);
  const Errors adapted = warming_run(true, &equivalent);
  std::printf(
      "warming 25 -> 45 degC, %g Hz loop: S_hat nrmse %.3f %% (last fifth %.3f %%), T_hat %.3f %% "
      "(%.3f %%) without adaptation; S_hat %.3f %% (%.3f %%), T_hat %.3f %% (%.3f %%) with it; "
      "equivalent temperature at the end %.2f degC (plant 45)\n",
      testing::kProcessTestRate, 100 * plain.s_nrmse, 100 * plain.s_last_nrmse, 100 * plain.t_nrmse,
      100 * plain.t_last_nrmse, 100 * adapted.s_nrmse, 100 * adapted.s_last_nrmse,
      100 * adapted.t_nrmse, 100 * adapted.t_last_nrmse, equivalent);
  // About 1.3x the measured figures (docs/daemon.md).
  EXPECT_LT(adapted.s_nrmse, 1.3 * kMeasuredAdaptedS);
  EXPECT_LT(adapted.t_nrmse, 1.3 * kMeasuredAdaptedT);
  EXPECT_LT(adapted.s_last_nrmse, 1.3 * kMeasuredAdaptedLastS);
  EXPECT_LT(adapted.t_last_nrmse, 1.3 * kMeasuredAdaptedLastT);
  EXPECT_GT(plain.s_nrmse, kMeasuredPlainS / 1.3);  // the warming is there to be corrected
  EXPECT_GT(plain.t_nrmse, kMeasuredPlainT / 1.3);
  EXPECT_NEAR(equivalent, 45.0, kMeasuredTemperatureError * 1.3);
}

// The same warming with the simulated driver's temperature channel (adaptation.use_temperature:
// the measured temperature replaces the estimate, read with the configured coefficients per K;
// the shipped model carries no fitted ones). Beside the figures above without it.
TEST(DaemonAdaptation, TheTemperatureChannelTracksTheWarmingStack) {
  double reported = 0.0;
  double shown = 0.0;
  const Errors measured = warming_run(true, &reported, true, &shown);
  std::printf(
      "warming 25 -> 45 degC, %g Hz loop, the temperature channel: S_hat nrmse %.3f %% (last "
      "fifth %.3f %%), T_hat %.3f %% (%.3f %%); temperature reported at the end %.2f degC "
      "(plant 45)\n",
      testing::kProcessTestRate, 100 * measured.s_nrmse, 100 * measured.s_last_nrmse,
      100 * measured.t_nrmse, 100 * measured.t_last_nrmse, reported);
  EXPECT_LT(measured.s_nrmse, 1.3 * kMeasuredChannelS);
  EXPECT_LT(measured.t_nrmse, 1.3 * kMeasuredChannelT);
  EXPECT_LT(measured.s_last_nrmse, 1.3 * kMeasuredChannelLastS);
  EXPECT_LT(measured.t_last_nrmse, 1.3 * kMeasuredChannelLastT);
  EXPECT_NEAR(reported, 45.0, 0.1);  // the plant's own temperature, as the driver reads it
  EXPECT_NEAR(shown, 45.0, 0.1) << "status estimate.temp";
}

}  // namespace
}  // namespace selfsense::daemon
