// The recorder's counters as Prometheus metric families (selfsense_recorder_*), for the daemon's
// telemetry file. Not real-time code (allocates).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "selfsense/daemon/prometheus.hpp"
#include "selfsense/daemon/recorder.hpp"

namespace selfsense::daemon {

// labels go on every sample (for instance {"board", "b1"}).
[[nodiscard]] std::vector<MetricFamily> recorder_metrics(
    const RecorderCounters& counters,
    const std::vector<std::pair<std::string, std::string>>& labels = {});

}  // namespace selfsense::daemon
