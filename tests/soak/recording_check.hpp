// What the soak test asserts on the daemon's recordings, read back with the project's reader
// (io::read_recording_csv, what `selfsense` uses): every loop cycle present once, in order,
// across the rotated files; each planned fault reaching the safe output in the cycle its cause
// appeared and staying latched until the reset; the loop re-armed and tracking after each reset;
// no fault latched that the plan or the timing statistics do not explain.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "soak/fault_plan.hpp"

namespace selfsense::soak {

struct RecordingExpectations {
  double rate_hz{10000.0};
  double safe_value{0.0};  // the command while faulted (safety.safe_output: zero)
  double watchdog_s{0.5};
  std::int64_t last_cycle{0};     // the daemon's "stopped at cycle N"
  bool overruns_shown{false};     // timing.overruns > 0 at the end: an overrun fault is explained
  double settle_s{0.3};           // after arming, before tracking is scored
  double score_s{1.0};            // tracking scored over this long (or until the next item)
  double tracking_rms_max{2e-5};  // RMS of S_hat - setpoint [strain] in the scored window
};

struct EpisodeFigures {
  std::string name{};
  std::int64_t onset_cycle{0};
  bool armed_before{false};        // the loop was armed in the cycle before the onset
  std::int64_t latched_cycles{0};  // onset to reset
  std::int64_t rearm_cycles{0};    // onset to armed again (-1: never)
  double tracking_rms{-1.0};       // S_hat - setpoint after the re-arm (-1: not scored)
};

struct RecordingReport {
  std::size_t files{0};
  std::int64_t rows{0};
  std::int64_t first_cycle{0};
  std::int64_t last_cycle{0};
  std::int64_t missing_cycles{0};
  std::int64_t overrun_faults{0};  // kOverrun latches (explained by the timing statistics)
  std::vector<EpisodeFigures> episodes{};
  std::vector<std::string> failures{};
};

// Reads DIRECTORY/selfsensed-*.csv in name order (one recording, its rotations) and checks them
// against the plan.
[[nodiscard]] RecordingReport check_recordings(const std::filesystem::path& directory,
                                               const std::vector<PlannedFault>& plan,
                                               const RecordingExpectations& expect);

}  // namespace selfsense::soak
