// What the loop publishes for the status request, the telemetry and the systemd STATUS= line:
// a plain value copied out every `status_period` cycles (LatestValue in spsc_ring.hpp), so
// readers on other threads never wait for, nor stall, the loop.
#pragma once

#include <array>
#include <cstdint>

#include "selfsense/adaptation/health_alarms.hpp"
#include "selfsense/adaptation/health_estimator.hpp"
#include "selfsense/models/sample_status.hpp"
#include "selfsense/runtime/driver.hpp"
#include "selfsense/runtime/loop_sample.hpp"
#include "selfsense/runtime/supervisor.hpp"

namespace selfsense::runtime {

// The online drift estimate (adaptation/drift_estimator.hpp) as the loop runs it.
struct AdaptationStatus {
  bool enabled{false};           // the loop runs the adapted reconstruction
  bool frozen{false};            // learning nothing, holding the estimate
  double permittivity{0.0};      // epsilon [1]: relative change of the permittivity
  double loop{0.0};              // lambda [1]: relative change of the hysteresis loop
  double temperature_degc{0.0};  // the equivalent temperature [degC]
  std::uint64_t updates{0};      // RLS updates since the start (or the restored state's)
};

// The health estimate (adaptation/health_estimator.hpp) and its alarms (health_alarms.hpp).
struct HealthStatus {
  bool enabled{false};
  bool fault{false};  // an alarm is a fault of the loop too (health.fault)
  adaptation::HealthFigures figures{};
  std::uint32_t active{0};   // alarm bits beyond their bands now
  std::uint32_t latched{0};  // alarm bits latched until a reset
  std::array<double, adaptation::kHealthAlarmCount> raised_at_s{};  // loop time; < 0: not latched
};

struct StatusSnapshot {
  std::int64_t cycle{0};
  LoopSample last{};
  LoopState state{LoopState::kFaulted};
  ControlMode mode{ControlMode::kPosition};
  std::uint32_t faults{0};  // latched bits
  std::array<FaultRecord, kFaultCount> fault_records{};
  std::array<std::uint64_t, models::kSampleStatusCount> estimate_status{};
  DriverCounters driver{};
  std::uint64_t commands{0};
  std::uint64_t saturations{0};
  std::uint64_t samples_dropped{0};  // the sample sink (recorder) refused them
  std::uint64_t model_swaps{0};
  bool wave_running{false};
  AdaptationStatus adaptation{};
  HealthStatus health{};
  // Timing, filled by the thread that runs the loop (runtime/loop_runner).
  std::int64_t overruns{0};
  std::int64_t missed_periods{0};
  std::int64_t wake_latency_p50_ns{0};
  std::int64_t wake_latency_p99_ns{0};
  std::int64_t wake_latency_max_ns{0};
  std::int64_t cycle_time_p50_ns{0};
  std::int64_t cycle_time_p99_ns{0};
  std::int64_t cycle_time_max_ns{0};
  std::int64_t last_overrun_cycle{-1};
};

}  // namespace selfsense::runtime
