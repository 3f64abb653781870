#include "selfsense/adaptation/health_estimator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace selfsense::adaptation {

namespace {

bool reject(std::string* why, const std::string& message) {
  if (why != nullptr) *why = message;
  return false;
}

constexpr double kSecondsPerHour{3600.0};

}  // namespace

bool HealthEstimatorConfig::is_valid(const std::string& prefix, std::string* why) const {
  const struct {
    const char* key;
    double value;
  } positive[] = {{"reversal_field_v_per_m", reversal_field_v_per_m},
                  {"hold_field_v_per_m", hold_field_v_per_m},
                  {"hold_window_s", hold_window_s},
                  {"min_hold_field_v_per_m", min_hold_field_v_per_m},
                  {"trend_time_s", trend_time_s},
                  {"slope_time_s", slope_time_s}};
  for (const auto& p : positive) {
    if (!(std::isfinite(p.value) && p.value > 0.0)) {
      return reject(why, prefix + p.key + ": must be finite and > 0");
    }
  }
  if (!(std::isfinite(hold_settle_s) && hold_settle_s >= 0.0)) {
    return reject(why, prefix + "hold_settle_s: must be finite and >= 0");
  }
  if (!(std::isfinite(settle_s) && settle_s >= 0.0)) {
    return reject(why, prefix + "settle_s: must be finite and >= 0");
  }
  if (!(slope_time_s > trend_time_s)) {
    return reject(why, prefix + "slope_time_s: must be > trend_time_s");
  }
  if (baseline_cycles < 1) return reject(why, prefix + "baseline_cycles: must be >= 1");
  if (!(span_tolerance > 0.0 && span_tolerance < 1.0)) {
    return reject(why, prefix + "span_tolerance: must be in (0, 1)");
  }
  if (!std::isfinite(capacitance_per_k) || capacitance_per_k == 0.0) {
    return reject(why, prefix + "capacitance_per_k: must be finite and not 0");
  }
  if (!std::isfinite(dissipation_per_k)) {
    return reject(why, prefix + "dissipation_per_k: must be finite");
  }
  if (!(depolarisation_sensitivity > 0.0 && depolarisation_sensitivity <= 2.0)) {
    return reject(why, prefix + "depolarisation_sensitivity: must be in (0, 2]");
  }
  if (!(max_span_change > 0.0 && max_span_change <= 1.0)) {
    return reject(why, prefix + "max_span_change: must be in (0, 1]");
  }
  return true;
}

HealthEstimator::HealthEstimator(const HealthEstimatorConfig& config, double sample_time_s)
    : config_{config},
      capacitance_{config.trend_time_s, config.slope_time_s},
      dissipation_{config.trend_time_s, config.slope_time_s},
      depolarisation_{config.trend_time_s, config.slope_time_s},
      conductivity_{config.trend_time_s, config.slope_time_s} {
  std::string why;
  if (!config_.is_valid("health.", &why)) throw std::invalid_argument{why};
  if (!(sample_time_s > 0.0 && std::isfinite(sample_time_s))) {
    throw std::invalid_argument{"health: the sample time must be > 0"};
  }
  ts_ = sample_time_s;
}

double HealthEstimator::time_s() const noexcept {
  return static_cast<double>(samples_) * ts_;
}

bool HealthEstimator::step(double field, double sensed, double predicted, bool accepted) noexcept {
  ++samples_;
  if (!accepted || !std::isfinite(field) || !std::isfinite(sensed)) {
    drop();
    return false;
  }
  const std::uint64_t before = cycles_;
  follow_reversals(field, sensed, predicted);
  follow_hold(field, sensed);
  last_e_ = field;
  last_d_ = sensed;
  last_p_ = predicted;
  return cycles_ != before;
}

void HealthEstimator::drop() noexcept {
  has_last_ = false;
  direction_ = 0;
  in_cycle_ = false;
  top_seen_ = false;
  in_hold_ = false;
}

void HealthEstimator::follow_reversals(double e, double d, double p) noexcept {
  const double delta = config_.reversal_field_v_per_m;
  if (!has_last_) {
    has_last_ = true;
    first_e_ = e;
    extreme_e_ = e;
    extreme_d_ = d;
    return;
  }
  if (in_cycle_) {
    area_ += 0.5 * (e + last_e_) * (d - last_d_);
    area_p_ += 0.5 * (e + last_e_) * (p - last_p_);  // NaN from a missing prediction on
  }
  if (direction_ == 0) {
    // The first move of delta sets the direction; no reversal is declared before it.
    if (std::abs(e - first_e_) >= delta) {
      direction_ = e > first_e_ ? 1 : -1;
      extreme_e_ = e;
      extreme_d_ = d;
    }
    return;
  }
  const bool rising = direction_ > 0;
  if (rising ? e >= extreme_e_ : e <= extreme_e_) {
    extreme_e_ = e;
    extreme_d_ = d;
    return;
  }
  if (std::abs(e - extreme_e_) < delta) return;
  const double c_rev = (d - extreme_d_) / (e - extreme_e_);
  on_reversal(!rising, e, d, p, extreme_e_, c_rev);
  direction_ = rising ? -1 : 1;
  extreme_e_ = e;
  extreme_d_ = d;
}

void HealthEstimator::on_reversal(bool at_minimum, double e, double d, double p, double extreme_e,
                                  double c_rev) noexcept {
  if (!at_minimum) {
    if (in_cycle_) {
      top_seen_ = true;
      cycle_max_e_ = extreme_e;
      cycle_c_sum_ += c_rev;
    }
    return;
  }
  if (in_cycle_ && top_seen_) finish_cycle(e, d, p);
  in_cycle_ = true;
  top_seen_ = false;
  area_ = 0.0;
  area_p_ = 0.0;
  start_e_ = e;
  start_d_ = d;
  start_p_ = p;
  cycle_min_e_ = extreme_e;
  cycle_c_sum_ = c_rev;
}

void HealthEstimator::finish_cycle(double e, double d, double p) noexcept {
  const double w = area_ + 0.5 * (e + start_e_) * (start_d_ - d);
  const double wp = area_p_ + 0.5 * (e + start_e_) * (start_p_ - p);  // NaN: no prediction
  const double c = 0.5 * cycle_c_sum_;
  const double t = time_s();
  if (!std::isfinite(w) || !std::isfinite(c)) return;
  ++cycles_;
  capacitance_.update(c, t);
  dissipation_.update(w, t);

  const auto same_extremes = [this](double span) {
    const double tol = config_.span_tolerance * span;
    return std::abs(cycle_min_e_ - base_min_) <= tol && std::abs(cycle_max_e_ - base_max_) <= tol;
  };
  const double base_span = base_max_ - base_min_;
  if (base_n_ < static_cast<double>(config_.baseline_cycles)) {
    if (has_extremes_ && !same_extremes(base_span)) {  // the drive changed: anew
      has_extremes_ = false;
      base_n_ = 0.0;
    }
    if (!has_extremes_ || t - base_start_s_ < config_.settle_s) {
      if (!has_extremes_) base_start_s_ = t;
      has_extremes_ = true;
      base_min_ = cycle_min_e_;
      base_max_ = cycle_max_e_;
      return;
    }
    const double k = base_n_ + 1.0;
    base_c_ = k == 1.0 ? c : base_c_ + (c - base_c_) / k;
    base_w_ = k == 1.0 ? w : base_w_ + (w - base_w_) / k;
    if (!(wp > 0.0)) {
      base_wp_ = -1.0;  // a baseline cycle without a prediction: none for this baseline
    } else if (k == 1.0 || base_wp_ > 0.0) {
      base_wp_ = k == 1.0 ? wp : base_wp_ + (wp - base_wp_) / k;
    }
    base_min_ = base_min_ + (cycle_min_e_ - base_min_) / k;
    base_max_ = base_max_ + (cycle_max_e_ - base_max_) / k;
    base_n_ = k;
    return;
  }
  if (!(base_c_ != 0.0) || !(base_w_ > 0.0)) return;
  const bool by_model = config_.model_reference && base_wp_ > 0.0 && wp > 0.0;
  if (by_model) {
    const double span = cycle_max_e_ - cycle_min_e_;
    if (!(std::abs(span / base_span - 1.0) <= config_.max_span_change)) return;
  } else if (!same_extremes(base_span)) {
    return;
  }
  const double ratio = by_model ? (w / wp) / (base_w_ / base_wp_) : w / base_w_;
  const double rise = (c / base_c_ - 1.0) / config_.capacitance_per_k;
  const double expected = std::max(1.0 + config_.dissipation_per_k * rise, 0.05);
  depolarisation_.update((1.0 - ratio / expected) / config_.depolarisation_sensitivity, t);
  ++compared_;
}

void HealthEstimator::follow_hold(double e, double d) noexcept {
  const double t = time_s();
  if (!in_hold_ || std::abs(e - hold_e_) > config_.hold_field_v_per_m) {
    in_hold_ = true;
    hold_e_ = e;
    hold_start_s_ = t;
    window_start_s_ = t + config_.hold_settle_s;
    n_ = st_ = stt_ = sd_ = std_ = se_ = 0.0;
    return;
  }
  if (t < window_start_s_) return;
  const double tau = t - window_start_s_;
  n_ += 1.0;
  st_ += tau;
  stt_ += tau * tau;
  sd_ += d;
  std_ += tau * d;
  se_ += e;
  if (tau < config_.hold_window_s) return;
  const double det = n_ * stt_ - st_ * st_;
  const double mean_e = se_ / n_;
  if (det > 0.0 && std::abs(mean_e) >= config_.min_hold_field_v_per_m) {
    const double slope = (n_ * std_ - st_ * sd_) / det;
    conductivity_.update(slope / mean_e, t);
    ++holds_;
  }
  window_start_s_ = t + ts_;
  n_ = st_ = stt_ = sd_ = std_ = se_ = 0.0;
}

HealthFigures HealthEstimator::figures() const noexcept {
  HealthFigures f;
  const auto relative = [](const TrendFilter& x) {
    return x.value() != 0.0 ? x.slope() * kSecondsPerHour / x.value() : 0.0;
  };
  f.has_capacitance = capacitance_.has_value();
  f.capacitance_f_per_m = capacitance_.value();
  f.capacitance_per_h = relative(capacitance_);
  f.has_dissipation = dissipation_.has_value();
  f.dissipation_j_per_m3 = dissipation_.value();
  f.dissipation_per_h = relative(dissipation_);
  f.baseline_ready = base_n_ >= static_cast<double>(config_.baseline_cycles);
  f.has_depolarisation = depolarisation_.has_value();
  f.depolarisation = depolarisation_.value();
  f.depolarisation_per_h = depolarisation_.slope() * kSecondsPerHour;
  f.has_leakage = conductivity_.has_value();
  f.leakage_conductivity_s_per_m = conductivity_.value();
  f.leakage_conductivity_per_h = conductivity_.slope() * kSecondsPerHour;
  f.leakage_resistivity_ohm_m = conductivity_.value() > 0.0
                                    ? 1.0 / conductivity_.value()
                                    : std::numeric_limits<double>::infinity();
  f.cycles = cycles_;
  f.compared_cycles = compared_;
  f.holds = holds_;
  return f;
}

void HealthEstimator::save_state(std::span<double> out) const noexcept {
  if (out.size() < kStateSize) return;
  const double head[12] = {static_cast<double>(samples_),
                           has_extremes_ ? 1.0 : 0.0,
                           base_start_s_,
                           base_n_,
                           base_c_,
                           base_w_,
                           base_min_,
                           base_max_,
                           static_cast<double>(cycles_),
                           static_cast<double>(compared_),
                           static_cast<double>(holds_),
                           base_wp_};
  std::copy(std::begin(head), std::end(head), out.begin());
  std::size_t at = 12;
  for (const TrendFilter* f : {&capacitance_, &dissipation_, &depolarisation_, &conductivity_}) {
    f->save_state(out.subspan(at, TrendFilter::kStateSize));
    at += TrendFilter::kStateSize;
  }
}

void HealthEstimator::restore_state(std::span<const double> in) noexcept {
  if (in.size() < kStateSize) return;
  const auto count = [](double v) {
    return std::isfinite(v) && v > 0.0 ? static_cast<std::uint64_t>(v) : std::uint64_t{0};
  };
  samples_ = count(in[0]);
  has_extremes_ = in[1] != 0.0;
  base_start_s_ = in[2];
  base_n_ = std::max(0.0, in[3]);
  base_c_ = in[4];
  base_w_ = in[5];
  base_min_ = in[6];
  base_max_ = in[7];
  cycles_ = count(in[8]);
  compared_ = count(in[9]);
  holds_ = count(in[10]);
  base_wp_ = in[11];
  std::size_t at = 12;
  for (TrendFilter* f : {&capacitance_, &dissipation_, &depolarisation_, &conductivity_}) {
    f->restore_state(in.subspan(at, TrendFilter::kStateSize));
    at += TrendFilter::kStateSize;
  }
  drop();
}

}  // namespace selfsense::adaptation
