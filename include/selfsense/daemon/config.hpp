// The daemon's configuration: one YAML file, plain structs with defaults, loaded strictly
// (unknown keys and wrong types are errors naming file, line and key path) and validated with
// every problem named (`selfsense check-config`). Not real-time code.
//
//   selfsensed: 1                       # format version
//   loop: {rate_hz, priority, cpu, allow_degraded_timing, status_period_cycles}
//   model: PATH                         # a model file from `selfsense identify` (relative paths
//                                       # are relative to this file)
//   model_state: PATH                   # optional: the model's memory, written at a clean stop
//                                       # and taken at the next start (model_state_file.hpp)
//   driver: {type: simulated, plant: PATH, ...}     # the driver's own keys, see drivers/
//   control:
//     mode: position | force | open-loop | damping
//     feedforward: true
//     command_v_per_m: [min, max]       # amplifier command range as field E
//     force_direction: -1               # sign of dT/dE of the mount
//     position: {kp, ki, kd, derivative_filter_s, setpoint_weight, tracking_time_s}
//     force: {...}                      # the same keys; E per Pa
//     position_shaper: {slew_per_s, filter: none|first-order|second-order, time_constant_s}
//     force_shaper: {...}
//     damping: {law: ppf|velocity, gain, frequency_hz, damping, dc_block_hz}
//     filters: [{type: notch, frequency_hz, quality, bandwidth_hz, depth_db},
//               {type: low-pass, frequency_hz, quality}, ...]        # at most 4
//   safety:
//     safe_output: zero | hold
//     safe_value_v_per_m: 0
//     strain_range: [min, max]          # physical range of S_hat
//     stress_range_pa: [min, max]       # of T_hat
//     setpoint_strain: [min, max]       # accepted setpoints in position, open-loop, damping
//     setpoint_stress_pa: [min, max]    # in force
//     overrun: {consecutive, within_count, window_cycles}
//     watchdog_s: 0                     # 0: off
//   recorder: {directory, rotate_bytes, flush_ms, ring_capacity, flight_recorder_s,
//              record_at_start}
//   socket: {path, group, max_clients}
//   telemetry: {prometheus_file, period_s}
//   adaptation:                         # online drift estimate (docs/adaptation.md)
//     enabled: false                    # true: the loop runs adaptation::AdaptedReconstruction
//     frozen: false                     # start with learning frozen (ctl adapt resume)
//     learn_loop, min_field_step_v_per_m, max_interval_s, memory_updates, initial_variance,
//     process_noise_per_s, max_relative_change, reference_degc, permittivity_per_k,
//     loop_per_k, coupling_per_k, compliance_per_k,
//     load_stiffness_ratio              # adaptation::DriftEstimatorConfig's keys
//     thermal_model, thermal_resistance_k_per_w, thermal_time_constant_s, ambient_degc,
//     stack_volume_m3, max_power_w      # adaptation::ThermalModelConfig's keys
//     use_temperature: false            # true: the driver's temp replaces the estimate
//     feedforward_estimate: false       # true: the feedforward's inverse takes the actuator
//                                       # adapted from the estimate too (not only a measured
//                                       # temperature with fitted coefficients)
//   health:                             # health from E and D, alarms (docs/health.md)
//     enabled: false                    # true: the loop runs adaptation::HealthEstimator
//     fault: false                      # true: an alarm is also a fault (safe output)
//     max_temperature_degc, max_depolarisation_pct, min_leakage_resistivity_ohm_m  # the bands
//     reversal_field_v_per_m, settle_s, baseline_cycles, span_tolerance, hold_field_v_per_m,
//     hold_settle_s, hold_window_s, min_hold_field_v_per_m, trend_time_s, slope_time_s,
//     capacitance_per_k, dissipation_per_k, depolarisation_sensitivity
//                                       # adaptation::HealthEstimatorConfig's keys
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "selfsense/adaptation/drift_estimator.hpp"
#include "selfsense/adaptation/health_alarms.hpp"
#include "selfsense/adaptation/health_estimator.hpp"
#include "selfsense/control/filter_design.hpp"
#include "selfsense/io/yaml_map.hpp"
#include "selfsense/runtime/controller.hpp"
#include "selfsense/runtime/loop.hpp"

namespace selfsense::daemon {

inline constexpr int kConfigFormatVersion = 1;

struct LoopSection {
  double rate_hz{10000.0};
  int priority{80};           // SCHED_FIFO 1..99
  int cpu{-1};                // affinity; -1: any
  int cpu_dma_latency_us{0};  // CPU wake-up latency requested while running; -1: none
  bool allow_degraded_timing{false};
  std::uint32_t status_period_cycles{100};
  friend bool operator==(const LoopSection&, const LoopSection&) = default;
};

struct FilterSection {
  std::string type{};  // notch | low-pass | high-pass | low-pass-1 | high-pass-1
  double frequency_hz{0.0};
  double quality{0.0};
  double bandwidth_hz{0.0};
  double depth_db{40.0};
  friend bool operator==(const FilterSection&, const FilterSection&) = default;
};

struct Range {
  double min{0.0};
  double max{0.0};
  friend bool operator==(const Range&, const Range&) = default;
};

struct SafetySection {
  runtime::SafeOutput safe_output{runtime::SafeOutput::kZero};
  double safe_value_v_per_m{0.0};
  Range strain{-2e-3, 3e-3};
  Range stress_pa{-1e8, 1e8};
  Range setpoint_strain{-1e-4, 1.5e-3};
  Range setpoint_stress_pa{-3e7, 1e7};
  runtime::OverrunPolicy overrun{};
  double watchdog_s{0.0};
  double stop_ramp_s{0.05};  // SIGTERM while armed: ramp to the safe output over this; 0: step
  friend bool operator==(const SafetySection&, const SafetySection&) = default;
};

struct RecorderSection {
  std::filesystem::path directory{"/var/lib/selfsensed"};
  std::uint64_t rotate_bytes{256ULL << 20U};
  double flush_ms{200.0};
  std::size_t ring_capacity{1U << 18U};  // about 13 s at 20 kHz
  double flight_recorder_s{5.0};
  bool record_at_start{false};
  friend bool operator==(const RecorderSection&, const RecorderSection&) = default;
};

struct SocketSection {
  std::filesystem::path path{"/run/selfsensed/control.sock"};
  std::string group{};  // empty: the daemon's own group
  int max_clients{16};
  friend bool operator==(const SocketSection&, const SocketSection&) = default;
};

struct TelemetrySection {
  std::filesystem::path prometheus_file{};  // empty: none
  double period_s{1.0};
  friend bool operator==(const TelemetrySection&, const TelemetrySection&) = default;
};

// The online adaptation of the reconstruction (adaptation/adapted_reconstruction.hpp).
struct AdaptationSection {
  bool enabled{false};
  adaptation::DriftEstimatorConfig estimator{};  // `frozen` is the estimator's
  // The driver's temperature (temp_ref) replaces the estimate in every cycle it is finite
  // (AdaptedReconstruction::set_temperature: with the model's fitted temperature coefficients,
  // docs/adaptation.md); in a cycle without it the estimate serves again.
  bool use_temperature{false};
  // The feedforward's inverse takes the actuator adapted from the drift estimated from E and D
  // too, not only at a measured temperature (runtime::LoopConfig::
  // adaptation_feedforward_estimate).
  bool feedforward_estimate{false};
  friend bool operator==(const AdaptationSection&, const AdaptationSection&) = default;
};

// The health estimate and its alarm bands (adaptation/health_estimator.hpp, health_alarms.hpp).
struct HealthSection {
  bool enabled{false};
  adaptation::HealthEstimatorConfig estimator{};
  adaptation::HealthBands bands{};  // `fault` is the bands'
  friend bool operator==(const HealthSection&, const HealthSection&) = default;
};

struct DaemonConfig {
  std::filesystem::path source{};  // the file it was read from
  LoopSection loop{};
  std::filesystem::path model{};
  std::filesystem::path model_state{};  // the model's memory across restarts; empty: not kept
  std::string driver_type{};
  std::string driver_section{};  // the `driver` mapping as text (a reload compares it)
  runtime::ControllerConfig control{};
  std::vector<FilterSection> filters{};
  SafetySection safety{};
  RecorderSection recorder{};
  SocketSection socket{};
  TelemetrySection telemetry{};
  AdaptationSection adaptation{};
  HealthSection health{};

  [[nodiscard]] double sample_time() const noexcept { return 1.0 / loop.rate_hz; }
  // The loop's configuration (sample time, safety) from these sections.
  [[nodiscard]] runtime::LoopConfig loop_config() const;
};

// A loaded configuration and the problems found in it. A structural problem (YAML syntax,
// unknown key, wrong type) ends the loading; every value and cross-field problem is collected.
struct ConfigResult {
  DaemonConfig config{};
  std::vector<std::string> problems{};  // "FILE:LINE: KEY.PATH: what is wrong"
  // Every key path the loader and the driver registry asked for, present in the file or not
  // (io::YamlMap::known_keys); each has a reload class (reload_keys.hpp). Filled when the file
  // was read to its end.
  std::vector<std::string> known_keys{};
  [[nodiscard]] bool ok() const noexcept { return problems.empty(); }
};

// The driver's own section is read by the driver registry (drivers/registry.hpp), given the
// open map: it reads its keys and returns its problems.
class DriverSectionReader {
 public:
  DriverSectionReader() = default;
  DriverSectionReader(const DriverSectionReader&) = delete;
  DriverSectionReader& operator=(const DriverSectionReader&) = delete;
  DriverSectionReader(DriverSectionReader&&) = delete;
  DriverSectionReader& operator=(DriverSectionReader&&) = delete;
  virtual ~DriverSectionReader() = default;
  // Reads `driver` (type already taken) and appends problems located with driver.locate().
  virtual void read(io::YamlMap& driver, const DaemonConfig& config,
                    std::vector<std::string>& problems) = 0;
};

// Never throws for a bad file: every problem goes into the result.
[[nodiscard]] ConfigResult load_config(const std::filesystem::path& path,
                                       DriverSectionReader* driver_reader);

}  // namespace selfsense::daemon
