// Telemetry in the Prometheus text exposition format 0.0.4, written as a file for
// node_exporter's textfile collector (--collector.textfile.directory), so that a fleet of boards
// is watched with the tools people already run.
//
//   # HELP selfsense_recorder_rows_written_total Rows written to recording files.
//   # TYPE selfsense_recorder_rows_written_total counter
//   selfsense_recorder_rows_written_total{board="b1"} 1200000
//
// Names are checked ([a-zA-Z_:][a-zA-Z0-9_:]* for metrics, [a-zA-Z_][a-zA-Z0-9_]* for labels,
// no label starting with "__"); label values escape \ " and line feed, HELP text \ and line
// feed; values print as integers when they are whole numbers below 2^53, else in the shortest
// round-trip form, with NaN, +Inf and -Inf spelled as the format wants.
//
// Not real-time code: everything here allocates and may throw; the daemon calls it from a
// telemetry thread with counters read from atomics and LatestValue snapshots.
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace selfsense::daemon {

class MetricError final : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

enum class MetricType { kCounter, kGauge };

struct MetricSample {
  std::vector<std::pair<std::string, std::string>> labels{};
  double value{0.0};
};

struct MetricFamily {
  std::string name{};
  std::string help{};
  MetricType type{MetricType::kGauge};
  std::vector<MetricSample> samples{};
};

[[nodiscard]] bool valid_metric_name(std::string_view name) noexcept;
[[nodiscard]] bool valid_label_name(std::string_view name) noexcept;

// The exposition text. Throws MetricError naming the metric or label that is not valid, or a
// metric name given twice.
[[nodiscard]] std::string format_exposition(const std::vector<MetricFamily>& families);

// Replaces path atomically: writes PATH's directory/.NAME.tmp (not matched by the collector's
// *.prom), fsyncs it and renames it over path, so a reader sees the old file or the new one,
// never a part. Throws std::runtime_error naming the file and the cause.
void write_textfile(const std::filesystem::path& path, std::string_view text);

}  // namespace selfsense::daemon
