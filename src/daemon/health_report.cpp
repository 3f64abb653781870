#include "selfsense/daemon/health_report.hpp"

#include <cmath>
#include <cstddef>
#include <string>
#include <utility>

#include "selfsense/adaptation/health_alarms.hpp"

namespace selfsense::daemon {
namespace {

nlohmann::json figure(bool has, double value) {
  return has && std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

}  // namespace

nlohmann::json health_json(const runtime::HealthStatus& h, std::string_view state_at_start) {
  if (!h.enabled) return {{"enabled", false}};
  const adaptation::HealthFigures& f = h.figures;
  nlohmann::json alarms = nlohmann::json::object();
  for (std::size_t i = 0; i < adaptation::kHealthAlarmCount; ++i) {
    const std::uint32_t b = 1U << i;
    alarms[std::string(adaptation::to_string(static_cast<adaptation::HealthAlarm>(i)))] = {
        {"active", (h.active & b) != 0U},
        {"latched", (h.latched & b) != 0U},
        {"raised_at_s",
         (h.latched & b) != 0U ? nlohmann::json(h.raised_at_s[i]) : nlohmann::json(nullptr)}};
  }
  nlohmann::json out = {
      {"enabled", true},
      {"fault", h.fault},
      {"capacitance_f_per_m", figure(f.has_capacitance, f.capacitance_f_per_m)},
      {"capacitance_change_per_h", figure(f.has_capacitance, f.capacitance_per_h)},
      {"dissipation_j_per_m3", figure(f.has_dissipation, f.dissipation_j_per_m3)},
      {"dissipation_change_per_h", figure(f.has_dissipation, f.dissipation_per_h)},
      {"baseline_ready", f.baseline_ready},
      {"depolarisation_pct", figure(f.has_depolarisation, 100.0 * f.depolarisation)},
      {"depolarisation_pct_per_h", figure(f.has_depolarisation, 100.0 * f.depolarisation_per_h)},
      {"leakage_resistivity_ohm_m", figure(f.has_leakage, f.leakage_resistivity_ohm_m)},
      {"leakage_conductivity_s_per_m", figure(f.has_leakage, f.leakage_conductivity_s_per_m)},
      {"cycles", f.cycles},
      {"compared_cycles", f.compared_cycles},
      {"holds", f.holds},
      {"alarms", std::move(alarms)}};
  if (!state_at_start.empty()) out["state_at_start"] = std::string(state_at_start);
  return out;
}

std::vector<MetricFamily> health_metrics(const runtime::HealthStatus& h) {
  using T = MetricType;
  std::vector<MetricFamily> out;
  if (!h.enabled) return out;
  const adaptation::HealthFigures& f = h.figures;
  const auto gauge = [&out](bool has, const char* name, const char* help, double value) {
    if (!has || std::isnan(value)) return;
    out.push_back(MetricFamily{
        std::string("selfsense_health_") + name, help, T::kGauge, {MetricSample{{}, value}}});
  };
  gauge(f.has_capacitance, "capacitance_farads_per_metre",
        "Capacitance at the field's reversals, dD/dE (slow value).", f.capacitance_f_per_m);
  gauge(f.has_capacitance, "capacitance_change_per_hour",
        "Relative slope of the capacitance per hour.", f.capacitance_per_h);
  gauge(f.has_dissipation, "dissipation_joules_per_cubic_metre",
        "Loop area per drive cycle, the energy lost per cycle and volume (slow value).",
        f.dissipation_j_per_m3);
  gauge(f.has_dissipation, "dissipation_change_per_hour",
        "Relative slope of the dissipation per hour.", f.dissipation_per_h);
  gauge(f.has_depolarisation, "depolarisation_ratio",
        "Loss of polarisation against the baseline, warming taken out (0.05: 5 %).",
        f.depolarisation);
  gauge(f.has_depolarisation, "depolarisation_change_per_hour",
        "Slope of the loss of polarisation per hour.", f.depolarisation_per_h);
  gauge(f.has_leakage, "leakage_resistivity_ohm_metres",
        "Leakage resistivity from holds (+Inf: no leakage seen).", f.leakage_resistivity_ohm_m);
  out.push_back(MetricFamily{"selfsense_health_cycles_total",
                             "Drive cycles measured.",
                             T::kCounter,
                             {MetricSample{{}, static_cast<double>(f.cycles)}}});
  out.push_back(MetricFamily{"selfsense_health_holds_total",
                             "Leakage windows measured on holds.",
                             T::kCounter,
                             {MetricSample{{}, static_cast<double>(f.holds)}}});
  MetricFamily active{"selfsense_health_alarm_active",
                      "1 while the alarm's figure is beyond its band.",
                      T::kGauge,
                      {}};
  MetricFamily latched{
      "selfsense_health_alarm_latched", "1 while the alarm is latched.", T::kGauge, {}};
  for (std::size_t i = 0; i < adaptation::kHealthAlarmCount; ++i) {
    const std::uint32_t b = 1U << i;
    const std::string name(adaptation::to_string(static_cast<adaptation::HealthAlarm>(i)));
    active.samples.push_back({{{"alarm", name}}, (h.active & b) != 0U ? 1.0 : 0.0});
    latched.samples.push_back({{{"alarm", name}}, (h.latched & b) != 0U ? 1.0 : 0.0});
  }
  out.push_back(std::move(active));
  out.push_back(std::move(latched));
  return out;
}

}  // namespace selfsense::daemon
