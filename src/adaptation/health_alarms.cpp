#include "selfsense/adaptation/health_alarms.hpp"

#include <cmath>

#include "selfsense/base/check.hpp"

namespace selfsense::adaptation {

std::string_view to_string(HealthAlarm a) noexcept {
  switch (a) {
    case HealthAlarm::kOverheating:
      return "overheating";
    case HealthAlarm::kDepolarisation:
      return "depolarisation";
    case HealthAlarm::kInsulation:
      return "insulation";
    case HealthAlarm::kCount:
      break;
  }
  return "unknown";
}

bool HealthBands::is_valid(const std::string& prefix, std::string* why) const {
  namespace check = base::check;
  const auto key = [&prefix](const char* name) { return prefix + name; };
  return check::finite(key("max_temperature_degc"), max_temperature_degc, why) &&
         check::require(max_depolarisation_pct > 0.0 && max_depolarisation_pct < 100.0,
                        key("max_depolarisation_pct"), max_depolarisation_pct,
                        "must be within (0, 100)", why) &&
         check::positive(key("min_leakage_resistivity_ohm_m"), min_leakage_resistivity_ohm_m, why);
}

std::uint32_t HealthAlarms::evaluate(const HealthFigures& f, bool has_temperature,
                                     double temperature_degc, double t_s) noexcept {
  std::uint32_t now = 0;
  if (has_temperature && temperature_degc > bands_.max_temperature_degc) {
    now |= bit(HealthAlarm::kOverheating);
  }
  if (f.has_depolarisation && 100.0 * f.depolarisation > bands_.max_depolarisation_pct) {
    now |= bit(HealthAlarm::kDepolarisation);
  }
  if (f.has_leakage && f.leakage_resistivity_ohm_m < bands_.min_leakage_resistivity_ohm_m) {
    now |= bit(HealthAlarm::kInsulation);
  }
  for (std::size_t i = 0; i < kHealthAlarmCount; ++i) {
    const std::uint32_t b = 1U << i;
    if ((now & b) != 0U && (latched_ & b) == 0U) raised_at_s_[i] = t_s;
  }
  active_ = now;
  latched_ |= now;
  return now;
}

std::uint32_t HealthAlarms::reset() noexcept {
  latched_ &= active_;
  for (std::size_t i = 0; i < kHealthAlarmCount; ++i) {
    if ((latched_ & (1U << i)) == 0U) raised_at_s_[i] = -1.0;
  }
  return latched_;
}

void HealthAlarms::save_state(std::span<double> out) const noexcept {
  if (out.size() < kStateSize) return;
  out[0] = static_cast<double>(latched_);
  for (std::size_t i = 0; i < kHealthAlarmCount; ++i)
    out[1 + i] = raised_at_s_[i];
}

void HealthAlarms::restore_state(std::span<const double> in) noexcept {
  if (in.size() < kStateSize) return;
  constexpr std::uint32_t kAll = (1U << kHealthAlarmCount) - 1U;
  const double bits = in[0];
  latched_ = std::isfinite(bits) && bits >= 0.0 && bits <= static_cast<double>(kAll)
                 ? static_cast<std::uint32_t>(bits)
                 : 0U;
  active_ = 0;
  for (std::size_t i = 0; i < kHealthAlarmCount; ++i) {
    const bool latched = (latched_ & (1U << i)) != 0U;
    raised_at_s_[i] = latched && std::isfinite(in[1 + i]) ? in[1 + i] : -1.0;
  }
}

}  // namespace selfsense::adaptation
