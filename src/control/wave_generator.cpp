#include "selfsense/control/wave_generator.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>
#include <string_view>
#include <utility>

#include "selfsense/base/format_number.hpp"
#include "selfsense/control/parameter_error.hpp"

namespace selfsense::control {
namespace {

using Shape = WaveGenerator::Shape;

constexpr double kWholeTolerance = 1e-9;  // relative: a period this close to whole samples is
constexpr double kMaxFrequencyFraction = 0.45;

bool has_natural_period(Shape shape) noexcept {
  return shape == Shape::kStaircase || shape == Shape::kTable;
}

std::string indexed(std::string_view name, std::size_t i) {
  return std::string(name) + '[' + std::to_string(i) + ']';
}

bool all_finite(std::string_view name, const std::vector<double>& values, std::string* why) {
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!check::finite(indexed(name, i), values[i], why)) return false;
  }
  return true;
}

bool valid_table(const WaveGenerator::Config& c, std::string* why) {
  if (c.table_values.size() < 2) {
    return check::fail("WaveGenerator.table_values",
                       "needs at least 2 values, has " + std::to_string(c.table_values.size()),
                       why);
  }
  if (!all_finite("WaveGenerator.table_values", c.table_values, why)) return false;
  if (c.table_times.empty()) return check::positive("WaveGenerator.table_dt", c.table_dt, why);
  if (c.table_times.size() != c.table_values.size()) {
    return check::fail("WaveGenerator.table_times",
                       "has " + std::to_string(c.table_times.size()) + " times for " +
                           std::to_string(c.table_values.size()) + " table_values",
                       why);
  }
  if (!all_finite("WaveGenerator.table_times", c.table_times, why)) return false;
  for (std::size_t i = 1; i < c.table_times.size(); ++i) {
    if (!(c.table_times[i] > c.table_times[i - 1])) {
      return check::fail(indexed("WaveGenerator.table_times", i),
                         base::format_number(c.table_times[i]) + " must be > " +
                             indexed("WaveGenerator.table_times", i - 1) + " = " +
                             base::format_number(c.table_times[i - 1]),
                         why);
    }
  }
  return true;
}

double natural_period(const WaveGenerator::Config& c) noexcept {
  switch (c.shape) {
    case Shape::kStaircase:
      return static_cast<double>(c.levels.size()) * c.dwell;
    case Shape::kTable:
      return c.table_times.empty() ? static_cast<double>(c.table_values.size() - 1) * c.table_dt
                                   : c.table_times.back() - c.table_times.front();
    default:
      return 0.0;
  }
}

// Which parameter sets the period, for messages.
std::string_view period_parameter(const WaveGenerator::Config& c) noexcept {
  if (c.frequency > 0.0 || !has_natural_period(c.shape)) return "WaveGenerator.frequency";
  if (c.shape == Shape::kStaircase) return "WaveGenerator.dwell";
  return c.table_times.empty() ? "WaveGenerator.table_dt" : "WaveGenerator.table_times";
}

// Floor-modulo for a positive period; exact when x and period are whole numbers.
double position_in_period(double x, double period) noexcept {
  double pos = x - std::floor(x / period) * period;
  if (pos >= period) pos -= period;
  return pos < 0.0 ? 0.0 : pos;
}

}  // namespace

bool WaveGenerator::Config::is_valid(double sample_time, std::string* why) const {
  if (!check::positive("WaveGenerator.sample_time", sample_time, why) ||
      !check::finite("WaveGenerator.amplitude", amplitude, why) ||
      !check::finite("WaveGenerator.offset", offset, why) ||
      !check::non_negative("WaveGenerator.phase", phase, why) ||
      !check::below("WaveGenerator.phase", phase, 1.0, "one cycle", why)) {
    return false;
  }
  if (has_natural_period(shape)) {
    if (!check::non_negative("WaveGenerator.frequency", frequency, why)) return false;
  } else if (!check::positive("WaveGenerator.frequency", frequency, why)) {
    return false;
  }
  if (frequency > 0.0 &&
      !check::below("WaveGenerator.frequency", frequency, kMaxFrequencyFraction / sample_time,
                    "0.45 * sample rate", why)) {
    return false;
  }
  if (shape == Shape::kStaircase) {
    if (levels.empty()) return check::fail("WaveGenerator.levels", "must not be empty", why);
    if (!all_finite("WaveGenerator.levels", levels, why)) return false;
    if (frequency == 0.0 && !check::positive("WaveGenerator.dwell", dwell, why)) return false;
  }
  if (shape == Shape::kTable && !valid_table(*this, why)) return false;
  const double period = frequency > 0.0 ? 1.0 / frequency : natural_period(*this);
  if (!(period / sample_time >= 2.0)) {
    return check::fail(
        period_parameter(*this),
        "gives a period of " + base::format_number(period / sample_time) + " samples, must be >= 2",
        why);
  }
  return true;
}

WaveGenerator::WaveGenerator(Config config, double sample_time)
    : config_(std::move(config)), ts_(sample_time) {
  std::string why;
  require_valid(config_.is_valid(sample_time, &why), why);
  natural_period_ = natural_period(config_);
  restart();
}

bool WaveGenerator::samples_for(double frequency, double* samples) const noexcept {
  if (!std::isfinite(frequency) || frequency < 0.0) return false;
  if (frequency == 0.0 && natural_period_ == 0.0) return false;
  if (frequency >= kMaxFrequencyFraction / ts_) return false;
  const double period = frequency > 0.0 ? 1.0 / frequency : natural_period_;
  double p = period / ts_;
  const double whole = std::round(p);
  if (std::abs(p - whole) <= kWholeTolerance * p) p = whole;
  if (!(p >= 2.0)) return false;
  *samples = p;
  return true;
}

void WaveGenerator::restart() noexcept {
  // Validated at construction, so the configured frequency always gives a period.
  [[maybe_unused]] const bool ok = samples_for(config_.frequency, &period_samples_);
  assert(ok);
  origin_ = config_.phase * period_samples_;
  count_ = 0;
  cycles_before_ = 0.0;
  done_ = false;
  hold_ = 0.0;
}

double WaveGenerator::cycles() const noexcept {
  return cycles_before_ + static_cast<double>(count_) / period_samples_;
}

double WaveGenerator::step() noexcept {
  if (done_) return hold_;
  if (config_.repeats > 0 && cycles() >= static_cast<double>(config_.repeats)) {
    done_ = true;
    hold_ = end_value();
    return hold_;
  }
  const double pos = position_in_period(origin_ + static_cast<double>(count_), period_samples_);
  ++count_;
  return config_.offset + config_.amplitude * unit_shape(pos);
}

double WaveGenerator::unit_shape(double pos) const noexcept {
  const double p = pos / period_samples_;
  switch (config_.shape) {
    case Shape::kSine:
      return std::sin(2.0 * std::numbers::pi * p);
    case Shape::kTriangle:
      if (p < 0.25) return 4.0 * p;
      if (p < 0.75) return 2.0 - 4.0 * p;
      return 4.0 * p - 4.0;
    case Shape::kSquare:
      return p < 0.5 ? 1.0 : -1.0;
    case Shape::kStaircase: {
      // pos * L / P, not p * L: one rounding, so stair edges fall on exact samples.
      const double levels = static_cast<double>(config_.levels.size());
      const auto i = static_cast<std::size_t>(std::floor(pos * levels / period_samples_));
      return config_.levels[std::min(i, config_.levels.size() - 1)];
    }
    case Shape::kTable:
      return table_at(pos);
  }
  return 0.0;
}

double WaveGenerator::table_at(double pos) const noexcept {
  const std::vector<double>& v = config_.table_values;
  const std::size_t last = v.size() - 1;
  std::size_t i = 0;
  double frac = 0.0;
  if (config_.table_times.empty()) {
    const double u = pos * static_cast<double>(last) / period_samples_;
    i = std::min(static_cast<std::size_t>(std::floor(u)), last - 1);
    frac = u - static_cast<double>(i);
  } else {
    const std::vector<double>& t = config_.table_times;
    const double tau = t.front() + pos / period_samples_ * (t.back() - t.front());
    const auto upper = std::upper_bound(t.begin(), t.end(), tau);
    const auto after = static_cast<std::size_t>(upper - t.begin());
    i = std::min(after == 0 ? 0 : after - 1, last - 1);
    frac = (tau - t[i]) / (t[i + 1] - t[i]);
  }
  frac = std::clamp(frac, 0.0, 1.0);
  return v[i] + frac * (v[i + 1] - v[i]);
}

double WaveGenerator::end_value() const noexcept {
  // Where the last period ends; a position at the period boundary is read from the left.
  const double remaining = static_cast<double>(config_.repeats) - cycles_before_;
  double pos = position_in_period(origin_ + remaining * period_samples_, period_samples_);
  constexpr double kEdge = 1e-6;  // samples
  if (pos < kEdge || period_samples_ - pos < kEdge) pos = period_samples_;
  return config_.offset + config_.amplitude * unit_shape(pos);
}

bool WaveGenerator::set_frequency(double frequency) noexcept {
  if (frequency == 0.0 && !has_natural_period(config_.shape)) return false;
  double samples = 0.0;
  if (!samples_for(frequency, &samples)) return false;
  const double pos = position_in_period(origin_ + static_cast<double>(count_), period_samples_);
  cycles_before_ = cycles();
  origin_ = pos / period_samples_ * samples;
  count_ = 0;
  period_samples_ = samples;
  return true;
}

void WaveGenerator::save_state(std::span<double> out) const noexcept {
  assert(out.size() >= kStateSize);
  out[0] = period_samples_;
  out[1] = origin_;
  out[2] = static_cast<double>(count_);
  out[3] = cycles_before_;
  out[4] = done_ ? 1.0 : 0.0;
  out[5] = hold_;
}

void WaveGenerator::restore_state(std::span<const double> in) noexcept {
  assert(in.size() >= kStateSize);
  period_samples_ = in[0];
  origin_ = in[1];
  count_ = static_cast<std::uint64_t>(in[2]);
  cycles_before_ = in[3];
  done_ = in[4] != 0.0;
  hold_ = in[5];
}

}  // namespace selfsense::control
