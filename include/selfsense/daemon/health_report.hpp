// The health estimate as the daemon reports it (docs/health.md): the status request's `health`
// object and the telemetry file's selfsense_health_* families. Not real-time code (allocates);
// fed from the loop's status snapshot.
//
// Status JSON `health` (with enabled false nothing else):
//   enabled, fault (alarms are faults too), capacitance_f_per_m, capacitance_change_per_h,
//   dissipation_j_per_m3, dissipation_change_per_h, baseline_ready, depolarisation_pct,
//   depolarisation_pct_per_h, leakage_resistivity_ohm_m, leakage_conductivity_s_per_m,
//   cycles, compared_cycles, holds (a figure not yet measured, or infinite, is null),
//   alarms: {overheating|depolarisation|insulation: {active, latched, raised_at_s}},
//   state_at_start (the daemon's: restored, none, not restored: WHY, off)
// Prometheus (only when enabled): selfsense_health_capacitance_farads_per_metre,
//   _capacitance_change_per_hour, _dissipation_joules_per_cubic_metre,
//   _dissipation_change_per_hour, _depolarisation_ratio, _depolarisation_change_per_hour,
//   _leakage_resistivity_ohm_metres, _cycles_total, _holds_total,
//   _alarm_active{alarm}, _alarm_latched{alarm} (a figure not yet measured is left out).
#pragma once

#include <nlohmann/json.hpp>
#include <string_view>
#include <vector>

#include "selfsense/daemon/prometheus.hpp"
#include "selfsense/runtime/status_snapshot.hpp"

namespace selfsense::daemon {

// state_at_start (when not empty): the `state_at_start` member (Daemon::health_state_at_start).
[[nodiscard]] nlohmann::json health_json(const runtime::HealthStatus& health,
                                         std::string_view state_at_start = {});
[[nodiscard]] std::vector<MetricFamily> health_metrics(const runtime::HealthStatus& health);

}  // namespace selfsense::daemon
