// The recorder's settings (the `recorder:` section of the daemon configuration), as a plain
// struct with defaults, and their validation. Loading from YAML is the configuration loader's
// job; validate() is where the limits live, so the loader, `selfsense check-config` and the
// Recorder's constructor agree.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace selfsense::daemon {

struct FlightRecorderConfig {
  double seconds{10.0};               // history kept in memory [s]
  bool dump_on_fault{true};           // dump when a sample shows a fault bit it did not have
  double post_trigger_seconds{1.0};   // keep recording this long after the fault, then dump [s]
  std::filesystem::path directory{};  // where automatic dumps go; empty: the recorder's
  std::string prefix{"flight"};       // automatic dumps: PREFIX-TIME-FAULTS.csv
};

struct RecorderConfig {
  std::filesystem::path directory{"."};               // where recordings go; must exist
  std::string prefix{"selfsense"};                    // files: PREFIX-YYYYmmddTHHMMSSZ-NNNN.csv
  std::size_t rotate_bytes{std::size_t{256} << 20U};  // a file never grows past this [bytes]
  double flush_period_ms{500.0};  // written rows reach the disk (fdatasync) at least this often
  std::size_t ring_capacity{std::size_t{1} << 16U};  // samples between loop and writer
  bool references{true};                             // write the reference columns S and T
  bool temperature{false};             // write `temp` (the driver's stack temperature, degC)
  bool temperature_equivalent{false};  // write `temp_equivalent` (the adaptation's, degC)
  double sample_time_s{1e-4};  // the loop's period, for the header comment and flight recorder
  std::vector<std::string> comments{};  // extra '#' lines for every file (config name, model)
  FlightRecorderConfig flight{};
};

// Every violated constraint, one line each, naming the key under `recorder.`:
// "recorder.rotate_bytes: must be >= 4096, got 100". Empty when valid.
[[nodiscard]] std::vector<std::string> validate(const RecorderConfig& config);

}  // namespace selfsense::daemon
