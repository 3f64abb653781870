#include "selfsense/adaptation/drift_estimator.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "selfsense/base/check.hpp"

namespace selfsense::adaptation {

bool DriftEstimatorConfig::is_valid(const std::string& prefix, std::string* why) const {
  namespace check = base::check;
  const auto key = [&prefix](const char* name) { return prefix + name; };
  const struct {
    const char* key;
    double value;
  } finite[] = {{"min_field_step_v_per_m", min_field_step_v_per_m},
                {"max_interval_s", max_interval_s},
                {"memory_updates", memory_updates},
                {"initial_variance", initial_variance},
                {"process_noise_per_s", process_noise_per_s},
                {"max_relative_change", max_relative_change},
                {"reference_degc", reference_degc},
                {"permittivity_per_k", permittivity_per_k},
                {"loop_per_k", loop_per_k},
                {"coupling_per_k", coupling_per_k},
                {"compliance_per_k", compliance_per_k},
                {"load_stiffness_ratio", load_stiffness_ratio}};
  for (const auto& f : finite) {
    if (!check::finite(key(f.key), f.value, why)) return false;
  }
  const bool valid = check::positive(key("min_field_step_v_per_m"), min_field_step_v_per_m, why) &&
                     check::positive(key("max_interval_s"), max_interval_s, why) &&
                     check::require(memory_updates > 1.0, key("memory_updates"), memory_updates,
                                    "must be > 1", why) &&
                     check::positive(key("initial_variance"), initial_variance, why) &&
                     check::non_negative(key("process_noise_per_s"), process_noise_per_s, why) &&
                     check::require(max_relative_change > 0.0 && max_relative_change < 1.0,
                                    key("max_relative_change"), max_relative_change,
                                    "must be within (0, 1)", why) &&
                     check::require(permittivity_per_k != 0.0, key("permittivity_per_k"),
                                    permittivity_per_k, "must not be 0", why) &&
                     check::non_negative(key("load_stiffness_ratio"), load_stiffness_ratio, why);
  return valid && (!thermal.enabled || thermal.is_valid(prefix, why));
}

DriftEstimator::DriftEstimator(const DriftEstimatorConfig& config, double sample_time_s, double c0)
    : config_{config} {
  std::string why;
  if (!config_.is_valid("adaptation.", &why)) throw std::invalid_argument{why};
  if (!(sample_time_s > 0.0 && std::isfinite(sample_time_s))) {
    throw std::invalid_argument{"adaptation: the sample time must be > 0"};
  }
  if (!(c0 > 0.0 && std::isfinite(c0))) {
    throw std::invalid_argument{
        "adaptation: the model's sensor side has no positive linear part (PI linear weight)"};
  }
  ts_ = sample_time_s;
  scale_ = 1.0 / (c0 * config_.min_field_step_v_per_m);
  mu_ = 1.0 - 1.0 / config_.memory_updates;
  growth_ = config_.process_noise_per_s * ts_;
  p_ = {config_.initial_variance, 0.0, 0.0, config_.learn_loop ? config_.initial_variance : 0.0};
}

bool DriftEstimator::step(double field, double sensed, double linear_part, double loop_part,
                          bool accepted) noexcept {
  if (!config_.frozen) grow_covariance();
  if (!accepted || !std::isfinite(field) || !std::isfinite(sensed) || !std::isfinite(linear_part) ||
      !std::isfinite(loop_part)) {
    anchored_ = false;
    return false;
  }
  if (!anchored_ || anchor_age_s_ > config_.max_interval_s) {
    anchored_ = true;
    anchor_e_ = field;
    anchor_d_ = sensed;
    anchor_l_ = linear_part;
    anchor_h_ = loop_part;
    anchor_age_s_ = 0.0;
    return false;
  }
  anchor_age_s_ += ts_;
  const double de = field - anchor_e_;
  if (std::abs(de) < config_.min_field_step_v_per_m) return false;
  const double dd = sensed - anchor_d_;
  const double dl = linear_part - anchor_l_;
  const double dh = loop_part - anchor_h_;
  anchor_e_ = field;
  anchor_d_ = sensed;
  anchor_l_ = linear_part;
  anchor_h_ = loop_part;
  anchor_age_s_ = 0.0;
  if (config_.frozen) return false;

  const double tie = config_.loop_per_k / config_.permittivity_per_k;
  const double phi0 = (config_.learn_loop ? dl : dl + tie * dh) * scale_;
  const double phi1 = config_.learn_loop ? dh * scale_ : 0.0;
  const double z = (dd - dh - dl) * scale_;
  // P phi and the gain.
  const double pp0 = p_[0] * phi0 + p_[1] * phi1;
  const double pp1 = p_[2] * phi0 + p_[3] * phi1;
  const double denom = mu_ + phi0 * pp0 + phi1 * pp1;
  if (!(denom > 0.0) || !std::isfinite(denom)) return false;
  const double k0 = pp0 / denom;
  const double k1 = pp1 / denom;
  const double err = z - (phi0 * theta_[0] + phi1 * theta_[1]);
  const double bound = config_.max_relative_change;
  theta_[0] = std::clamp(theta_[0] + k0 * err, -bound, bound);
  theta_[1] = config_.learn_loop ? std::clamp(theta_[1] + k1 * err, -bound, bound)
                                 : std::clamp(tie * theta_[0], -bound, bound);
  // P = (P - K (P phi)') / mu (P symmetric, so phi' P = (P phi)').
  std::array<double, 4> next{(p_[0] - k0 * pp0) / mu_, (p_[1] - k0 * pp1) / mu_,
                             (p_[2] - k1 * pp0) / mu_, (p_[3] - k1 * pp1) / mu_};
  const double sym = config_.learn_loop ? 0.5 * (next[1] + next[2]) : 0.0;
  next[1] = sym;
  next[2] = sym;
  if (!config_.learn_loop) next[3] = 0.0;
  const double trace = next[0] + next[3];
  const double limit = (config_.learn_loop ? 2.0 : 1.0) * config_.initial_variance;
  if (trace > limit) {
    for (double& v : next)
      v *= limit / trace;
  }
  p_ = next;
  ++updates_;
  return true;
}

void DriftEstimator::grow_covariance() noexcept {
  if (!(growth_ > 0.0)) return;
  p_[0] += growth_;
  if (config_.learn_loop) p_[3] += growth_;
  const double trace = p_[0] + p_[3];
  const double limit = (config_.learn_loop ? 2.0 : 1.0) * config_.initial_variance;
  if (trace > limit) {
    for (double& v : p_)
      v *= limit / trace;
  }
}

Drift DriftEstimator::drift() const noexcept {
  const double rise = theta_[0] / config_.permittivity_per_k;
  return Drift{theta_[0], theta_[1], config_.coupling_per_k * rise, config_.compliance_per_k * rise,
               config_.reference_degc + rise};
}

void DriftEstimator::set_temperature(double degc) noexcept {
  if (!std::isfinite(degc)) return;
  const double rise = degc - config_.reference_degc;
  set_drift(config_.permittivity_per_k * rise, config_.loop_per_k * rise);
}

void DriftEstimator::set_drift(double permittivity, double loop) noexcept {
  if (!std::isfinite(permittivity) || !std::isfinite(loop)) return;
  const double bound = config_.max_relative_change;
  theta_[0] = std::clamp(permittivity, -bound, bound);
  theta_[1] = std::clamp(loop, -bound, bound);
}

void DriftEstimator::carry(double delta_k) noexcept {
  if (config_.frozen || !std::isfinite(delta_k)) return;
  const double bound = config_.max_relative_change;
  theta_[0] = std::clamp(theta_[0] + config_.permittivity_per_k * delta_k, -bound, bound);
  theta_[1] = std::clamp(theta_[1] + config_.loop_per_k * delta_k, -bound, bound);
}

void DriftEstimator::save_state(std::span<double> out) const noexcept {
  if (out.size() < kStateSize) return;
  const double values[kStateSize] = {theta_[0],
                                     theta_[1],
                                     p_[0],
                                     p_[1],
                                     p_[2],
                                     p_[3],
                                     anchor_e_,
                                     anchor_d_,
                                     anchor_l_,
                                     anchor_h_,
                                     anchor_age_s_,
                                     anchored_ ? 1.0 : 0.0,
                                     static_cast<double>(updates_)};
  std::copy(std::begin(values), std::end(values), out.begin());
}

void DriftEstimator::restore_state(std::span<const double> in) noexcept {
  if (in.size() < kStateSize) return;
  const double bound = config_.max_relative_change;
  theta_ = {std::clamp(in[0], -bound, bound), std::clamp(in[1], -bound, bound)};
  p_ = {in[2], in[3], in[4], in[5]};
  anchor_e_ = in[6];
  anchor_d_ = in[7];
  anchor_l_ = in[8];
  anchor_h_ = in[9];
  anchor_age_s_ = in[10];
  anchored_ = in[11] != 0.0;
  updates_ = static_cast<std::size_t>(std::max(0.0, in[12]));
}

}  // namespace selfsense::adaptation
