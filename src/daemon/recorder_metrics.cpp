#include "selfsense/daemon/recorder_metrics.hpp"

#include <cstdint>

namespace selfsense::daemon {

std::vector<MetricFamily> recorder_metrics(
    const RecorderCounters& c, const std::vector<std::pair<std::string, std::string>>& labels) {
  std::vector<MetricFamily> families;
  const auto add = [&](const char* name, const char* help, MetricType type, double value) {
    families.push_back(MetricFamily{
        std::string("selfsense_recorder_") + name, help, type, {MetricSample{labels, value}}});
  };
  const auto count = [&](const char* name, const char* help, std::uint64_t value) {
    add(name, help, MetricType::kCounter, static_cast<double>(value));
  };
  count("samples_pushed_total", "Loop samples accepted into the recorder's ring.",
        c.samples_pushed);
  count("samples_dropped_total", "Loop samples refused because the ring was full.",
        c.samples_dropped);
  count("samples_unrecorded_total", "Samples consumed while no recording was on.",
        c.samples_unrecorded);
  count("rows_written_total", "Rows written to recording files.", c.rows_written);
  count("rows_flushed_total", "Rows written as of the last fdatasync.", c.rows_flushed);
  count("rows_lost_total", "Rows lost to write errors.", c.rows_lost);
  count("rows_bad_time_total", "Samples not written because t was not finite.", c.rows_bad_time);
  count("time_breaks_total", "Files started because t did not increase.", c.time_breaks);
  count("files_total", "Recording files created.", c.files);
  count("bytes_written_total", "Bytes written to recording files.", c.bytes_written);
  count("flushes_total", "Successful fdatasync calls.", c.flushes);
  count("write_errors_total", "Failed open, write, link or fdatasync calls.", c.write_errors);
  count("flight_dumps_total", "Flight recorder dumps written.", c.flight_dumps);
  count("flight_dump_errors_total", "Flight recorder dumps that failed.", c.flight_dump_errors);
  add("ring_high_water", "Most samples waiting in the ring at once.", MetricType::kGauge,
      static_cast<double>(c.ring_high_water));
  add("recording", "1 while a recording file is open.", MetricType::kGauge,
      c.recording ? 1.0 : 0.0);
  return families;
}

}  // namespace selfsense::daemon
