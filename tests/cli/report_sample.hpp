// A synthetic diagnosis for the report tests: two channels (S, D) driven by a decaying sine
// with steps, two findings, correlation tests before and after, and hostile text in the paths.
#pragma once

#include <cmath>
#include <cstddef>
#include <numbers>
#include <vector>

#include "selfsense/report/diagnose_report.hpp"

namespace selfsense::test {

inline std::vector<double> sample_correlation(std::size_t count, double decay, double scale) {
  std::vector<double> out(count);
  for (std::size_t i = 0; i < count; ++i) {
    out[i] =
        scale * std::exp(-decay * static_cast<double>(i)) * std::cos(0.4 * static_cast<double>(i));
  }
  return out;
}

inline report::ReportCorrelation sample_test(const std::string& channel, double scale) {
  report::ReportCorrelation c;
  c.channel = channel;
  c.max_lag = 25;
  c.autocorrelation = sample_correlation(26, 0.15, 1.0);
  c.autocorrelation[0] = 1.0;
  std::vector<double> cross(51);
  for (std::size_t i = 0; i < cross.size(); ++i) {
    const double lag = static_cast<double>(i) - 25.0;
    cross[i] = scale * std::exp(-std::abs(lag) / 6.0) * (lag >= 0 ? 1.0 : 0.4);
  }
  c.cross_correlation = cross;
  c.bound = 0.08;
  return c;
}

// n samples at 1 kHz.
inline report::ReportInput make_sample_report(std::size_t n) {
  report::ReportInput in;
  in.model_path = "models/<script>alert(1)</script>.yaml";
  in.recording_path = "data/run \"A\" & 'B'.csv";
  in.validate_path = "data/validation.csv";
  in.verdict = "mismatch";
  in.t.resize(n);
  in.drive.resize(n);
  const double fs = 1000.0;
  const double duration = static_cast<double>(n) / fs;
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) / fs;
    in.t[i] = t;
    const double envelope = 1.0 - 0.8 * t / duration;
    in.drive[i] = 1.0e6 + 0.9e6 * envelope * std::sin(2.0 * std::numbers::pi * 2.0 * t);
  }

  const char* names[] = {"S", "D"};
  const char* units[] = {"-", "C/m^2"};
  const double gains[] = {1.0e-9, 2.0e-8};
  for (std::size_t c = 0; c < 2; ++c) {
    report::ReportChannel ch;
    ch.name = names[c];
    ch.unit = units[c];
    ch.recorded.resize(n);
    ch.before.resize(n);
    ch.after.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const double t = in.t[i];
      const double lagged = 1.0e6 + 0.9e6 * (1.0 - 0.8 * t / duration) *
                                        std::sin(2.0 * std::numbers::pi * 2.0 * t - 0.35);
      const double creep = 0.02 * std::log10(1.0 + t);
      const double noise = 0.003 * std::sin(12345.678 * static_cast<double>(i));
      ch.recorded[i] = gains[c] * lagged * (1.0 + creep + noise);
      ch.before[i] = gains[c] * in.drive[i];
      ch.after[i] = gains[c] * lagged * (1.0 + creep);
    }
    ch.located = {{0.1 * duration, 0.2 * duration}, {0.6 * duration, 0.65 * duration}};
    ch.test_before = sample_test(ch.name, 0.5);
    ch.test_after = sample_test(ch.name, 0.05);
    in.fit_before.push_back({ch.name, 0.12 + 0.01 * static_cast<double>(c), 0.31});
    in.fit_after.push_back({ch.name, 0.004, 0.015});
    in.validation_before.push_back({ch.name, 0.13, 0.33});
    in.validation_after.push_back({ch.name, 0.005, 0.02});
    in.channels.push_back(std::move(ch));
  }

  const char* effects[] = {"creep", "charge_leakage"};
  const char* features[] = {"log10 time since last step [s]", "D integral [C s/m^2]"};
  for (std::size_t k = 0; k < 2; ++k) {
    report::ReportFinding f;
    f.effect = effects[k];
    f.channel = names[k];
    f.where = in.channels[k].located;
    f.explains = 0.83 - 0.2 * static_cast<double>(k);
    f.evidence = "residual rises with log time after each step (r = 0.91 > 0.5 & p < 1e-6)";
    if (k == 0) {
      f.alternatives.push_back(
          {"hysteresis", 0.7, "the recorded S differs on rising & falling branches <here>"});
    }
    f.feature_name = features[k];
    f.feature.resize(n);
    f.residual.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      f.feature[i] = std::log10(1.0e-3 + std::fmod(in.t[i], 1.7));
      f.residual[i] = in.channels[k].recorded[i] - in.channels[k].before[i];
    }
    in.findings.push_back(std::move(f));
  }
  return in;
}

}  // namespace selfsense::test
