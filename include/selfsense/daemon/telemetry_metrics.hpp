// The daemon's telemetry file (Prometheus text format, prometheus.hpp) as metric families: the
// loop's timing and state, fault counts per fault name, the driver's counters and the
// recorder's (recorder_metrics.hpp). Daemon::write_telemetry() joins them, formats them with
// format_exposition() and replaces the textfile. Names and types: docs/recorder.md ("The
// telemetry file").
//
// Driver counters: the common fields of runtime::DriverCounters are one counter family each,
// selfsense_driver_<field>_total{driver="spi"}; the driver's own counters (its events) are one
// family, selfsense_driver_events_total{driver="spi",event="no_new_data"}, so that a new event
// of a driver needs no new metric name.
//
// Not real-time code (allocates); fed from the loop's status snapshot and the recorder's atomics.
#pragma once

#include <string_view>
#include <vector>

#include "selfsense/daemon/prometheus.hpp"
#include "selfsense/runtime/driver.hpp"
#include "selfsense/runtime/status_snapshot.hpp"

namespace selfsense::daemon {

// selfsense_loop_*: state, cycles, latched faults, overruns, latencies (gauges, names as before
// these counters existed), commands, saturations, model swaps, estimate statuses and faults per
// name (counters).
[[nodiscard]] std::vector<MetricFamily> loop_metrics(const runtime::StatusSnapshot& status);

// selfsense_adaptation_*: the online drift estimate (docs/adaptation.md), only when the loop
// runs the adaptation: permittivity_change and loop_change [1], equivalent temperature_celsius,
// frozen (0/1) gauges and updates_total.
[[nodiscard]] std::vector<MetricFamily> adaptation_metrics(
    const runtime::AdaptationStatus& adaptation);

// selfsense_driver_*_total{driver=NAME} and selfsense_driver_events_total{driver,event}. An event
// without a name, or whose name repeats, is left out (a driver's bug must not make the file
// invalid).
[[nodiscard]] std::vector<MetricFamily> driver_metrics(std::string_view driver,
                                                       const runtime::DriverCounters& counters);

}  // namespace selfsense::daemon
