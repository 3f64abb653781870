#include "selfsense/daemon/telemetry_metrics.hpp"

#include <cmath>
#include <cstdint>
#include <set>
#include <string>
#include <utility>

#include "selfsense/models/sample_status.hpp"
#include "selfsense/runtime/supervisor.hpp"

namespace selfsense::daemon {
namespace {

MetricFamily one(std::string name, std::string help, MetricType type, double value,
                 std::vector<std::pair<std::string, std::string>> labels = {}) {
  return MetricFamily{
      std::move(name), std::move(help), type, {MetricSample{std::move(labels), value}}};
}

double seconds(std::int64_t ns) {
  return static_cast<double>(ns) * 1e-9;
}

}  // namespace

std::vector<MetricFamily> loop_metrics(const runtime::StatusSnapshot& s) {
  using T = MetricType;
  std::vector<MetricFamily> f;
  f.push_back(one("selfsense_loop_state", "0 faulted, 1 ready, 2 armed", T::kGauge,
                  static_cast<double>(s.state)));
  f.push_back(one("selfsense_loop_cycles", "loop cycles since start", T::kGauge,
                  static_cast<double>(s.cycle)));
  f.push_back(one("selfsense_loop_faults_latched", "latched fault bits", T::kGauge,
                  static_cast<double>(s.faults)));
  f.push_back(one("selfsense_loop_overruns", "missed deadlines", T::kGauge,
                  static_cast<double>(s.overruns)));
  f.push_back(one("selfsense_loop_wake_latency_p99_seconds", "wake-up latency p99", T::kGauge,
                  seconds(s.wake_latency_p99_ns)));
  f.push_back(one("selfsense_loop_cycle_time_p99_seconds", "cycle execution time p99", T::kGauge,
                  seconds(s.cycle_time_p99_ns)));
  f.push_back(one("selfsense_loop_samples_dropped", "samples the recorder could not take",
                  T::kGauge, static_cast<double>(s.samples_dropped)));
  f.push_back(one("selfsense_loop_wake_latency_p50_seconds", "wake-up latency p50", T::kGauge,
                  seconds(s.wake_latency_p50_ns)));
  f.push_back(one("selfsense_loop_wake_latency_max_seconds", "wake-up latency maximum", T::kGauge,
                  seconds(s.wake_latency_max_ns)));
  f.push_back(one("selfsense_loop_cycle_time_max_seconds", "cycle execution time maximum",
                  T::kGauge, seconds(s.cycle_time_max_ns)));
  f.push_back(one("selfsense_loop_commands_total", "Commands the loop took from the socket.",
                  T::kCounter, static_cast<double>(s.commands)));
  f.push_back(one("selfsense_loop_saturations_total", "Cycles whose command was clamped.",
                  T::kCounter, static_cast<double>(s.saturations)));
  f.push_back(one("selfsense_loop_model_swaps_total", "Models swapped in while running.",
                  T::kCounter, static_cast<double>(s.model_swaps)));
  // Only while the driver measures it (none: the series ends rather than reading NaN).
  if (std::isfinite(s.last.temp_ref)) {
    f.push_back(one("selfsense_stack_temperature_celsius",
                    "The stack's temperature as the driver measures it.", T::kGauge,
                    s.last.temp_ref));
  }
  MetricFamily faults{"selfsense_loop_faults_total",
                      "Cycles in which each fault's cause was seen (status fault_details count).",
                      T::kCounter,
                      {}};
  for (std::size_t i = 0; i < runtime::kFaultCount; ++i) {
    faults.samples.push_back(
        {{{"fault", std::string(runtime::to_string(static_cast<runtime::Fault>(i)))}},
         static_cast<double>(s.fault_records[i].count)});
  }
  f.push_back(std::move(faults));
  MetricFamily estimates{"selfsense_loop_estimate_status_total",
                         "Reconstructed samples by the model's status.",
                         T::kCounter,
                         {}};
  for (std::size_t i = 0; i < models::kSampleStatusCount; ++i) {
    estimates.samples.push_back(
        {{{"status", std::string(models::to_string(static_cast<models::SampleStatus>(i)))}},
         static_cast<double>(s.estimate_status[i])});
  }
  f.push_back(std::move(estimates));
  return f;
}

std::vector<MetricFamily> adaptation_metrics(const runtime::AdaptationStatus& a) {
  using T = MetricType;
  std::vector<MetricFamily> f;
  if (!a.enabled) return f;
  f.push_back(one("selfsense_adaptation_permittivity_change",
                  "Estimated relative change of the permittivity against the model.", T::kGauge,
                  a.permittivity));
  f.push_back(one("selfsense_adaptation_loop_change",
                  "Estimated relative change of the hysteresis loop against the model.", T::kGauge,
                  a.loop));
  f.push_back(one("selfsense_adaptation_temperature_celsius",
                  "Equivalent temperature of the permittivity change.", T::kGauge,
                  a.temperature_degc));
  f.push_back(one("selfsense_adaptation_frozen", "1 while learning is frozen.", T::kGauge,
                  a.frozen ? 1.0 : 0.0));
  f.push_back(one("selfsense_adaptation_updates_total", "Updates of the drift estimate.",
                  T::kCounter, static_cast<double>(a.updates)));
  return f;
}

std::vector<MetricFamily> driver_metrics(std::string_view driver,
                                         const runtime::DriverCounters& c) {
  std::vector<MetricFamily> f;
  const std::vector<std::pair<std::string, std::string>> label{{"driver", std::string(driver)}};
  const auto count = [&](const char* field, const char* help, std::uint64_t v) {
    f.push_back(one(std::string("selfsense_driver_") + field + "_total", help, MetricType::kCounter,
                    static_cast<double>(v), label));
  };
  count("reads", "Driver read() calls while active.", c.reads);
  count("writes", "Commands the driver put out.", c.writes);
  count("errors", "Driver errors (failed transfers, error frames, failed transactions).", c.errors);
  count("timeouts", "Samples or answers that did not come in time.", c.timeouts);
  count("stale", "Reads answered stale.", c.stale);
  count("bad_data", "Reads or frames with bad data.", c.bad_data);
  count("crc_errors", "Frames whose CRC failed.", c.crc_errors);
  count("retries", "Retries after failures.", c.retries);
  count("reconnects", "Links or devices re-established.", c.reconnects);
  count("device_faults", "Faults the device reported.", c.device_faults);
  MetricFamily events{"selfsense_driver_events_total",
                      "The driver's own counters by name (docs/drivers/).",
                      MetricType::kCounter,
                      {}};
  std::set<std::string_view> seen;
  for (const runtime::NamedCount& e : c.event_list()) {
    if (e.name == nullptr || !seen.insert(e.name).second) continue;
    events.samples.push_back(
        {{{"driver", std::string(driver)}, {"event", e.name}}, static_cast<double>(e.value)});
  }
  if (!events.samples.empty()) f.push_back(std::move(events));
  return f;
}

}  // namespace selfsense::daemon
