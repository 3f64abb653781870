// What one soak run gathered, the verdict on it and its printout: the driver's status polls
// (the timing evidence), resident memory samples, the hostile clients' counts, the daemon's
// final status and exit, and the recordings' check.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <vector>

#include "soak/fault_plan.hpp"
#include "soak/recording_check.hpp"
#include "soak/socket_abuse.hpp"

namespace selfsense::soak {

// One status request of the driver: when it was sent (CLOCK_MONOTONIC), how long the answer
// took, and the loop's cycle and timing counts in it.
struct Poll {
  double wall_s{0.0};
  double rtt_s{0.0};
  std::int64_t cycles{0};
  std::int64_t missed_periods{0};
  std::int64_t overruns{0};
};

struct RssSample {
  double t_s{0.0};
  std::uint64_t bytes{0};
};

struct DriverFigures {
  std::uint64_t resets{0};
  std::uint64_t arms{0};
  std::uint64_t waves_stopped{0};
  std::uint64_t reload_requests{0};
  std::uint64_t client_errors{0};
};

struct Report {
  double seconds{0.0};
  double wall_s{0.0};
  double rate_hz{10000.0};
  std::vector<PlannedFault> plan{};
  std::vector<Poll> polls{};
  std::vector<RssSample> rss{};
  DriverFigures driver{};
  std::vector<std::string> driver_failures{};
  AbuseCounts abuse{};
  nlohmann::json final_status{};
  std::uint64_t sighups{0};
  std::size_t reloads_logged{0};
  std::size_t reloads_refused{0};
  int exit_status{-1};
  std::int64_t stopped_cycle{0};
  RecordingReport recordings{};

  // Filled by judge().
  std::vector<std::string> failures{};
  double rss_baseline_mib{0.0};  // max over 20-45 % of the run
  double rss_final_mib{0.0};     // max over the last quarter
  double rss_slope_kib_per_min{0.0};
  double timing_worst_gap_cycles{0.0};  // most deadlines neither run nor counted, any window
  std::int64_t deadlines{0};            // wall time x rate, first to last poll
  std::int64_t cycles_run{0};
  std::int64_t missed_counted{0};
  double poll_rtt_max_s{0.0};
  double poll_rtt_p99_s{0.0};
};

// Limits the verdict uses.
inline constexpr double kRssGrowthMaxMib = 4.0;
inline constexpr double kPollRttMaxS = 2.0;
inline constexpr double kTimingWindowS = 5.0;

// Every assertion; true when all hold (the failures are in report.failures).
bool judge(Report& report);
void print_report(const Report& report, std::ostream& out);

}  // namespace selfsense::soak
