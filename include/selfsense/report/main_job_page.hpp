// The main job's page (scripts/main_job.sh, `selfsense main-job-page`): per run of selfsensed,
// the figures line the report computed and plots read off the daemon's own recording, drawn
// with the reports' plotting code (svg_plot.hpp): time in s, strain in 1e-6, stress in MPa,
// field in kV/mm; the setpoint, the self-sensed estimate and the plant's true value; the
// tracking error under each run over the samples its figure counts; spans outside the armed
// state shaded and the moment a fault latched marked. One self-contained file, no scripts or
// network resources. This file only draws; evaluation/main_job_input.hpp reads the recordings.
#pragma once

#include <cstdint>
#include <filesystem>
#include <limits>
#include <span>
#include <string>
#include <vector>

namespace selfsense::report {

// Codes of the recording's `state` column (the daemon's recorder).
inline constexpr double kStateFaulted = 0.0;
inline constexpr double kStateArmed = 2.0;

// Where the report's tracking figure starts counting after a setpoint step, and the step it
// notices (scripts/main_job_report.sh): a setpoint change of more than 1 % of its range.
inline constexpr double kSettleTime = 0.2;             // [s]
inline constexpr double kSetpointStepFraction = 0.01;  // of the setpoint's range

struct MainJobRun {
  enum class Kind : std::uint8_t { kPosition, kForce, kRingDown };
  std::string heading{};  // "position", "damped", "position, run 1 of 2 (faulted)"
  Kind kind{Kind::kPosition};
  std::string figures{};    // the report's line for the run, shown as text
  std::string recording{};  // the recording's path, shown as text
  std::string error{};      // why there is no data (an unreadable recording); shown instead
  // The recording's columns (SI; daemon time t [s]); reference empty when not recorded.
  std::vector<double> t{};
  std::vector<double> setpoint{};   // S [-] (position) or T [Pa] (force)
  std::vector<double> estimate{};   // S_hat [-] or T_hat [Pa]
  std::vector<double> reference{};  // S [-] or T [Pa], the plant's truth
  std::vector<double> field{};      // E [V/m]
  std::vector<double> state{};      // 0 faulted, 1 ready, 2 armed
  // The control mode (0 position, 2 open-loop); empty when not recorded. A position run's
  // tracking error counts position-mode samples only (the self-heating run warms the stack in
  // open loop first).
  std::vector<double> mode{};
  // The self-heating run's temperatures [degC], empty when not recorded: the plant's stack
  // (`temp`) and the adaptation's equivalent temperature (`temp_equivalent`). With either, a
  // tracking run also plots them and the self-sensing error (estimate - reference).
  std::vector<double> temperature{};
  std::vector<double> temperature_estimate{};
  // The first faulted sample: its time and what latched ("overrun at cycle 65783").
  double fault_t{std::numeric_limits<double>::quiet_NaN()};
  std::string fault_text{};
};

struct MainJobPage {
  std::string title{"selfsensed on the simulated transducer"};
  std::vector<std::string> fault_lines{};  // the faulted runs, done again (faults.txt)
  std::vector<MainJobRun> runs{};
  std::vector<MainJobRun> faulted_runs{};  // the recordings the faulted runs spoiled
  std::vector<std::string> summary{};      // lines after the runs (the damping ratio)
};

// The samples a tracking figure counts: armed, not the first armed one, and at least
// kSettleTime after the last setpoint step among the armed samples.
[[nodiscard]] std::vector<bool> settled_samples(std::span<const double> t,
                                                std::span<const double> setpoint,
                                                std::span<const double> state);

// The ring-down plot's window and rests (scripts/main_job_report.sh): rest = the mean of the
// last 40 % of the armed samples; the window 0.4 s from 0.05 s before the largest deviation of
// the reference (the estimate when there is none) from its rest. Over armed samples only;
// valid false when there is none.
struct RingDownWindow {
  bool valid{false};
  double rest_reference{0.0};
  double rest_estimate{0.0};
  double t0{0.0};
  double t1{0.0};
};
[[nodiscard]] RingDownWindow ring_down_window(const MainJobRun& run);

[[nodiscard]] std::string main_job_page_html(const MainJobPage& page);
// Throws std::runtime_error naming the path when it cannot be written.
void write_main_job_page(const MainJobPage& page, const std::filesystem::path& path);

}  // namespace selfsense::report
