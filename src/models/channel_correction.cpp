#include "selfsense/models/channel_correction.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "selfsense/base/check.hpp"
#include "selfsense/models/cubic_read.hpp"

namespace selfsense::models {
namespace {

// "<name>: has 5 terms, at most 4" unless size <= limit.
bool at_most(const std::string& name, std::size_t size, std::size_t limit, const char* what,
             std::string* why) {
  return size <= limit || base::check::fail(name,
                                            "has " + std::to_string(size) + " " + what +
                                                ", at most " + std::to_string(limit),
                                            why);
}

}  // namespace

bool ChannelCorrection::is_valid(const std::string& prefix, std::string* why) const {
  const std::pair<const char*, double> scalars[] = {
      {"gain", gain},
      {"offset", offset},
      {"temperature_reference_degc", temperature_reference_degc},
      {"temperature_gain_per_k", temperature_gain_per_k},
      {"temperature_offset_per_k", temperature_offset_per_k},
      {"temperature_drive_per_k", temperature_drive_per_k},
      {"temperature_gain_per_k2", temperature_gain_per_k2},
      {"temperature_offset_per_k2", temperature_offset_per_k2},
      {"temperature_drive_per_k2", temperature_drive_per_k2},
      {"temperature_stress_per_k", temperature_stress_per_k},
      {"temperature_stress_per_k2", temperature_stress_per_k2},
      {"drive_integral_per_s", drive_integral_per_s},
      {"stress_gain_per_pa", stress_gain_per_pa},
      {"stress_quadratic_per_pa2", stress_quadratic_per_pa2},
      {"stress_drive_per_pa", stress_drive_per_pa},
      {"stress_linear_per_pa", stress_linear_per_pa},
      {"drive_quadratic", drive_quadratic},
      {"drive_cubic", drive_cubic},
      {"drive_linear", drive_linear},
      {"sensed_quadratic", sensed_quadratic},
      {"dynamics_frequency_hz", dynamics_frequency_hz},
      {"dynamics_damping", dynamics_damping},
      {"dynamics_direct", dynamics_direct},
      {"dynamics2_frequency_hz", dynamics2_frequency_hz},
      {"dynamics2_damping", dynamics2_damping},
      {"dynamics2_share", dynamics2_share},
      {"leakage_tau_s", leakage_tau_s},
      {"delay_s", delay_s}};
  namespace check = base::check;
  const auto key = [&prefix](const char* name) { return prefix + "." + name; };
  for (const auto& [name, value] : scalars) {
    if (!check::finite(key(name), value, why)) return false;
  }
  return check::same_size(key("creep_weights"), creep_weights.size(), key("creep_eigenvalues"),
                          creep_eigenvalues.size(), why) &&
         at_most(key("creep_eigenvalues"), creep_eigenvalues.size(), kMaxCorrectionCreep, "terms",
                 why) &&
         check::all_positive(key("creep_eigenvalues"), creep_eigenvalues, why) &&
         check::all_finite(key("creep_weights"), creep_weights, why) &&
         check::same_size(key("drive_creep_weights"), drive_creep_weights.size(),
                          key("drive_creep_eigenvalues"), drive_creep_eigenvalues.size(), why) &&
         at_most(key("drive_creep_eigenvalues"), drive_creep_eigenvalues.size(),
                 kMaxCorrectionCreep, "terms", why) &&
         check::all_positive(key("drive_creep_eigenvalues"), drive_creep_eigenvalues, why) &&
         check::all_finite(key("drive_creep_weights"), drive_creep_weights, why) &&
         check::require(dynamics_frequency_hz >= 0.0, key("dynamics_frequency_hz"),
                        dynamics_frequency_hz, "must be >= 0 (0: none)", why) &&
         check::require(dynamics_frequency_hz == 0.0 || dynamics_damping > 0.0,
                        key("dynamics_damping"), dynamics_damping,
                        "must be > 0 with a dynamics frequency", why) &&
         check::require(dynamics2_frequency_hz >= 0.0, key("dynamics2_frequency_hz"),
                        dynamics2_frequency_hz, "must be >= 0 (0: one mode)", why) &&
         check::require(dynamics2_frequency_hz == 0.0 || dynamics2_damping > 0.0,
                        key("dynamics2_damping"), dynamics2_damping,
                        "must be > 0 with a second mode's frequency", why) &&
         check::require(dynamics_frequency_hz > 0.0 || dynamics2_frequency_hz == 0.0,
                        key("dynamics2_frequency_hz"), dynamics2_frequency_hz,
                        "needs dynamics_frequency_hz (the first mode)", why) &&
         check::require(dynamics_frequency_hz > 0.0 || dynamics_direct == 0.0,
                        key("dynamics_direct"), dynamics_direct,
                        "needs dynamics_frequency_hz (the share of no mode beside one)", why) &&
         check::require(dynamics2_frequency_hz > 0.0 || dynamics2_share == 0.0,
                        key("dynamics2_share"), dynamics2_share,
                        "needs dynamics2_frequency_hz (the second mode)", why) &&
         check::require(leakage_tau_s >= 0.0, key("leakage_tau_s"), leakage_tau_s,
                        "must be >= 0 (0: none)", why) &&
         check::non_negative(key("delay_s"), delay_s, why) &&
         check::require(1.0 + gain > 0.0, key("gain"), gain, "must be > -1", why) &&
         plays_valid(prefix, why);
}

bool ChannelCorrection::plays_valid(const std::string& prefix, std::string* why) const {
  namespace check = base::check;
  const auto key = [&prefix](const char* name) { return prefix + "." + name; };
  if (!(check::same_size(key("hysteresis_weights"), hysteresis_weights.size(),
                         key("hysteresis_thresholds"), hysteresis_thresholds.size(), why) &&
        at_most(key("hysteresis_thresholds"), hysteresis_thresholds.size(), kMaxCorrectionPlays,
                "plays", why) &&
        check::strictly_increasing_above(key("hysteresis_thresholds"), hysteresis_thresholds, 0.0,
                                         why) &&
        check::all_finite(key("hysteresis_weights"), hysteresis_weights, why) &&
        check::same_size(key("hinge_levels"), hinge_levels.size(), key("hinge_thresholds"),
                         hinge_thresholds.size(), why) &&
        check::same_size(key("hinge_weights"), hinge_weights.size(), key("hinge_thresholds"),
                         hinge_thresholds.size(), why) &&
        at_most(key("hinge_thresholds"), hinge_thresholds.size(), kMaxCorrectionHinges, "hinges",
                why) &&
        check::all_finite(key("hinge_levels"), hinge_levels, why) &&
        check::all_finite(key("hinge_weights"), hinge_weights, why))) {
    return false;
  }
  for (std::size_t h = 0; h < hinge_thresholds.size(); ++h) {
    const double r = hinge_thresholds[h];
    const bool known =
        r == 0.0 || std::find(hysteresis_thresholds.begin(), hysteresis_thresholds.end(), r) !=
                        hysteresis_thresholds.end();
    if (!check::require(known, key("hinge_thresholds") + "[" + std::to_string(h) + "]", r,
                        "must be 0 or one of hysteresis_thresholds", why)) {
      return false;
    }
  }
  return true;
}

bool ChannelCorrection::invertible(const std::string& prefix, std::string* why) const {
  namespace check = base::check;
  return check::require(dynamics_frequency_hz == 0.0, prefix + ".dynamics_frequency_hz",
                        dynamics_frequency_hz,
                        "must be 0 (dynamics on the sensed channel are not inverted by the "
                        "reconstruction)",
                        why) &&
         check::require(sensed_quadratic == 0.0, prefix + ".sensed_quadratic", sensed_quadratic,
                        "must be 0 (only the strain channel may use it)", why);
}

bool ChannelCorrection::empty() const noexcept {
  return gain == 0.0 && offset == 0.0 && temperature_gain_per_k == 0.0 &&
         temperature_offset_per_k == 0.0 && temperature_drive_per_k == 0.0 &&
         temperature_gain_per_k2 == 0.0 && temperature_offset_per_k2 == 0.0 &&
         temperature_drive_per_k2 == 0.0 && temperature_stress_per_k == 0.0 &&
         temperature_stress_per_k2 == 0.0 && drive_integral_per_s == 0.0 &&
         drive_creep_weights.empty() && stress_gain_per_pa == 0.0 &&
         stress_quadratic_per_pa2 == 0.0 && stress_drive_per_pa == 0.0 &&
         stress_linear_per_pa == 0.0 && drive_quadratic == 0.0 && drive_cubic == 0.0 &&
         drive_linear == 0.0 && sensed_quadratic == 0.0 && creep_weights.empty() &&
         dynamics_frequency_hz == 0.0 && leakage_tau_s == 0.0 && delay_s == 0.0 &&
         hysteresis_weights.empty() && hinge_weights.empty();
}

ModeCoefficients mode_coefficients(double frequency_hz, double damping, double sample_time) {
  const double w0 = 2.0 * std::numbers::pi * frequency_hz;
  if (w0 * sample_time / 2.0 >= 0.95 * std::numbers::pi / 2.0) {
    throw std::invalid_argument(
        "correction.dynamics_frequency_hz: at or above Nyquist for this sample time");
  }
  const double k = w0 / std::tan(w0 * sample_time / 2.0);
  const double a0 = k * k + 2.0 * damping * w0 * k + w0 * w0;
  ModeCoefficients m;
  m.b0 = w0 * w0 / a0;
  m.a1 = (2.0 * w0 * w0 - 2.0 * k * k) / a0;
  m.a2 = (k * k - 2.0 * damping * w0 * k + w0 * w0) / a0;
  return m;
}

CorrectionStage::CorrectionStage(const ChannelCorrection& correction, double sample_time)
    : c_(correction) {
  std::string why;
  if (!c_.is_valid("correction", &why)) throw std::invalid_argument(why);
  if (!(sample_time > 0.0)) throw std::invalid_argument("correction: sample time must be > 0");
  creep_count_ = c_.creep_eigenvalues.size();
  drive_creep_count_ = c_.drive_creep_eigenvalues.size();
  ts_ = sample_time;
  for (std::size_t j = 0; j < drive_creep_count_; ++j) {
    drive_alpha_[j] = -std::expm1(-c_.drive_creep_eigenvalues[j] * sample_time);
  }
  play_count_ = c_.hysteresis_thresholds.size();
  std::copy(c_.hysteresis_thresholds.begin(), c_.hysteresis_thresholds.end(), play_r_.begin() + 1);
  hinge_count_ = c_.hinge_thresholds.size();
  const auto rows_end = play_r_.begin() + static_cast<std::ptrdiff_t>(1 + play_count_);
  for (std::size_t h = 0; h < hinge_count_; ++h) {
    const auto row = std::find(play_r_.begin(), rows_end, c_.hinge_thresholds[h]);
    hinge_row_[h] = static_cast<std::size_t>(row - play_r_.begin());
  }
  for (std::size_t j = 0; j < creep_count_; ++j) {
    alpha_[j] = -std::expm1(-c_.creep_eigenvalues[j] * sample_time);
  }
  if (c_.dynamics_frequency_hz > 0.0) {
    const ModeCoefficients m =
        mode_coefficients(c_.dynamics_frequency_hz, c_.dynamics_damping, sample_time);
    a1_ = m.a1;
    a2_ = m.a2;
    b0_ = m.b0;
    b1_ = 2.0 * b0_;
    b2_ = b0_;
    dynamics_ = true;
    if (c_.dynamics2_frequency_hz > 0.0) {
      second_ = mode_coefficients(c_.dynamics2_frequency_hz, c_.dynamics2_damping, sample_time);
    }
    direct_ = c_.dynamics_direct;
    second_share_ = c_.dynamics2_share;
    mixed_modes_ = direct_ != 0.0 || second_share_ != 0.0;
  }
  if (c_.leakage_tau_s > 0.0) {
    const double r = sample_time / c_.leakage_tau_s;
    leak_g_ = std::exp(-r);
    leak_c_ = -std::expm1(-r) / r;
    leakage_ = true;
  }
  if (c_.delay_s > 0.0) {
    const double samples = c_.delay_s / sample_time;
    if (samples > static_cast<double>(kMaxCorrectionDelaySamples)) {
      throw std::invalid_argument("correction.delay_s: more than " +
                                  std::to_string(kMaxCorrectionDelaySamples) +
                                  " samples at this sample time");
    }
    delay_whole_ = static_cast<std::size_t>(std::floor(samples));
    delay_frac_ = samples - static_cast<double>(delay_whole_);
    delay_ = true;
  }
}

// 1 + gain terms, kept away from zero: a temperature gain fitted over a few kelvin must not flip
// the sign or divide by zero far outside them.
double CorrectionStage::gain_at(const Inputs& in) const noexcept {
  const double dtheta = in.temperature - c_.temperature_reference_degc;
  return std::max(
      1.0 + c_.gain + (c_.temperature_gain_per_k + c_.temperature_gain_per_k2 * dtheta) * dtheta,
      0.05);
}

double CorrectionStage::terms(const Inputs& in) const noexcept {
  const double dtheta = in.temperature - c_.temperature_reference_degc;
  const double x = in.drive;
  return c_.offset +
         (c_.temperature_offset_per_k + c_.temperature_drive_per_k * x +
          (c_.temperature_offset_per_k2 + c_.temperature_drive_per_k2 * x) * dtheta) *
             dtheta +
         c_.drive_linear * x + c_.drive_quadratic * x * x + c_.drive_cubic * x * x * x +
         c_.sensed_quadratic * in.sensed * in.sensed;
}

double CorrectionStage::stress_coupling_change(const Inputs& in) const noexcept {
  const double dtheta = in.temperature - c_.temperature_reference_degc;
  return c_.stress_gain_per_pa * in.response + c_.stress_drive_per_pa * in.drive +
         c_.stress_linear_per_pa +
         (c_.temperature_stress_per_k + c_.temperature_stress_per_k2 * dtheta) * dtheta;
}

// Writes `value` into a ring and reads it back the configured delay later: below one sample by
// linear interpolation between the two samples around it (no later sample exists), from one
// sample on by the cubic through the two samples around it and one on each side
// (models/cubic_read.hpp), which does not low-pass what it reads.
double CorrectionStage::push_delayed(std::array<double, kLine>& line, std::size_t& head,
                                     double value) const noexcept {
  head = (head + 1) % kLine;
  line[head] = value;
  if (!delay_) return value;
  const auto back = [&](std::size_t samples) { return line[(head + kLine - samples) % kLine]; };
  const double a = back(delay_whole_);
  if (delay_frac_ == 0.0) return a;
  if (delay_whole_ == 0) return a + delay_frac_ * (back(1) - a);
  // The delayed instant lies 1 - frac after the older sample of the two around it.
  const std::array<double, 4> w = cubic_read_weights(1.0 - delay_frac_);
  return w[0] * back(delay_whole_ + 2) + w[1] * back(delay_whole_ + 1) + w[2] * a +
         w[3] * back(delay_whole_ - 1);
}

double CorrectionStage::delayed(double value) noexcept {
  return push_delayed(line_, head_, value);
}

double CorrectionStage::filters(double v) noexcept {
  double w = v;
  if (dynamics_) {
    w = b0_ * v + b1_ * v1_ + b2_ * v2_ - a1_ * w1_ - a2_ * w2_;
    w2_ = w1_;
    w1_ = w;
    if (mixed_modes_) {
      const double h2 =
          second_.b0 * (v + 2.0 * v1_ + v2_) - second_.a1 * second_w1_ - second_.a2 * second_w2_;
      second_w2_ = second_w1_;
      second_w1_ = h2;
      w += direct_ * (v - w) + second_share_ * (h2 - w);
    }
    v2_ = v1_;
    v1_ = v;
  }
  if (leakage_) {
    m_ = leak_g_ * m_ + leak_c_ * (w - w_prev_);
    w_prev_ = w;
    w = m_;
  }
  return delayed(w);
}

double CorrectionStage::play_terms(double drive) noexcept {
  if (play_count_ == 0 && hinge_count_ == 0) return 0.0;
  if (!plays_started_) {
    plays_started_ = true;
    plays_.fill(drive);
  }
  double sum = 0.0;
  for (std::size_t i = 0; i < play_count_; ++i) {
    const double r = play_r_[i + 1];
    plays_[i] = std::min(std::max(plays_[i], drive - r), drive + r);
    sum += c_.hysteresis_weights[i] * (plays_[i] - drive);
  }
  for (std::size_t h = 0; h < hinge_count_; ++h) {
    const std::size_t row = hinge_row_[h];
    const double p = row == 0 ? drive : plays_[row - 1];
    sum += c_.hinge_weights[h] * std::max(p - c_.hinge_levels[h], 0.0);
  }
  return sum;
}

double CorrectionStage::drive_memory_terms(double drive, double integral_start) noexcept {
  if (drive_creep_count_ == 0 && c_.drive_integral_per_s == 0.0) return 0.0;
  if (!memory_started_) {
    memory_started_ = true;
    x0_ = drive;
    u_.fill(drive);
    integral_ = integral_start;
  } else {
    integral_ += ts_ * drive;
  }
  double sum = c_.drive_integral_per_s * integral_;
  for (std::size_t j = 0; j < drive_creep_count_; ++j) {
    u_[j] += drive_alpha_[j] * (drive - u_[j]);
    sum += c_.drive_creep_weights[j] * (u_[j] - x0_);
  }
  return sum;
}

double CorrectionStage::step(const Inputs& in) noexcept {
  const bool first = !started_;
  if (first) {
    started_ = true;
    y0_ = in.response;
    for (std::size_t j = 0; j < creep_count_; ++j)
      z_[j] = in.response;
  }
  double v = in.y * gain_at(in) +
             (c_.stress_quadratic_per_pa2 * in.stress + stress_coupling_change(in)) * in.stress +
             terms(in) + play_terms(in.drive) + drive_memory_terms(in.drive, 0.0);
  for (std::size_t j = 0; j < creep_count_; ++j) {
    z_[j] += alpha_[j] * (in.response - z_[j]);
    v += c_.creep_weights[j] * (z_[j] - y0_);
  }
  if (first) {  // the filters start at the first value: no ringing, no decay yet
    v1_ = v2_ = w1_ = w2_ = second_w1_ = second_w2_ = v;
    m_ = w_prev_ = v;
    line_.fill(v);
    return v;
  }
  return filters(v);
}

double CorrectionStage::filter(double v) noexcept {
  if (!started_) {  // the filters start at the first value, as in step()
    started_ = true;
    v1_ = v2_ = w1_ = w2_ = second_w1_ = second_w2_ = v;
    m_ = w_prev_ = v;
    line_.fill(v);
    return v;
  }
  return filters(v);
}

double CorrectionStage::delay_drive(double drive) noexcept {
  if (!drive_started_) {
    drive_started_ = true;
    drive_line_.fill(drive);
  }
  return push_delayed(drive_line_, drive_head_, drive);
}

double CorrectionStage::invert(double measured, const Inputs& in) noexcept {
  double w = measured;
  if (leakage_) {
    if (started_) {
      w = w_prev_ + (measured - leak_g_ * m_) / leak_c_;
    }
    m_ = measured;  // the forward's first output is its input: the inverse's too
    w_prev_ = w;
  }
  if (!started_) {
    y0_ = in.response;
    for (std::size_t j = 0; j < creep_count_; ++j)
      z_[j] = in.response;
  }
  started_ = true;
  double creep = 0.0;  // lags of the response to the drive alone: known before y is
  for (std::size_t j = 0; j < creep_count_; ++j) {
    z_[j] += alpha_[j] * (in.response - z_[j]);
    creep += c_.creep_weights[j] * (z_[j] - y0_);
  }
  // The drive is delayed: its line starts full of x0, which the integral must not count.
  return (w - terms(in) - play_terms(in.drive) -
          drive_memory_terms(in.drive, -c_.delay_s * in.drive) - creep) /
         gain_at(in);
}

double CorrectionStage::solve_stress(double t_lin, double coupling,
                                     const Inputs& in) const noexcept {
  const double change = stress_coupling_change(in);
  if ((c_.stress_quadratic_per_pa2 == 0.0 && change == 0.0) || coupling == 0.0) return t_lin;
  const double g = gain_at(in);
  const double q = c_.stress_quadratic_per_pa2 / g;
  const double b = coupling + change / g;
  // q T^2 + b T - d T_lin = 0, the root that tends to d T_lin / b as q -> 0 (no cancellation).
  const double disc = b * b + 4.0 * q * coupling * t_lin;
  if (!(disc >= 0.0)) return -b / (2.0 * q);  // past the vertex: the nearest stress
  return 2.0 * coupling * t_lin / (b + std::copysign(std::sqrt(disc), b));
}

void CorrectionStage::save_state(std::span<double> out) const noexcept {
  std::size_t i = 0;
  const double head[17] = {started_ ? 1.0 : 0.0,
                           y0_,
                           v1_,
                           v2_,
                           w1_,
                           w2_,
                           m_,
                           w_prev_,
                           static_cast<double>(head_),
                           static_cast<double>(drive_head_),
                           drive_started_ ? 1.0 : 0.0,
                           plays_started_ ? 1.0 : 0.0,
                           memory_started_ ? 1.0 : 0.0,
                           x0_,
                           integral_,
                           second_w1_,
                           second_w2_};
  for (const double v : head)
    out[i++] = v;
  for (const double v : z_)
    out[i++] = v;
  for (const double v : u_)
    out[i++] = v;
  for (const double v : plays_)
    out[i++] = v;
  for (const double v : line_)
    out[i++] = v;
  for (const double v : drive_line_)
    out[i++] = v;
}

void CorrectionStage::restore_state(std::span<const double> in) noexcept {
  std::size_t i = 0;
  started_ = in[i++] != 0.0;
  y0_ = in[i++];
  v1_ = in[i++];
  v2_ = in[i++];
  w1_ = in[i++];
  w2_ = in[i++];
  m_ = in[i++];
  w_prev_ = in[i++];
  head_ = static_cast<std::size_t>(in[i++]) % kLine;
  drive_head_ = static_cast<std::size_t>(in[i++]) % kLine;
  drive_started_ = in[i++] != 0.0;
  plays_started_ = in[i++] != 0.0;
  memory_started_ = in[i++] != 0.0;
  x0_ = in[i++];
  integral_ = in[i++];
  second_w1_ = in[i++];
  second_w2_ = in[i++];
  for (double& v : z_)
    v = in[i++];
  for (double& v : u_)
    v = in[i++];
  for (double& v : plays_)
    v = in[i++];
  for (double& v : line_)
    v = in[i++];
  for (double& v : drive_line_)
    v = in[i++];
}

}  // namespace selfsense::models
