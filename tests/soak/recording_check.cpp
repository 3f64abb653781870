#include "soak/recording_check.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string_view>

#include "selfsense/io/recording.hpp"
#include "selfsense/runtime/loop_sample.hpp"
#include "selfsense/runtime/supervisor.hpp"

namespace selfsense::soak {
namespace {

constexpr auto kFaulted = static_cast<std::uint8_t>(runtime::LoopState::kFaulted);
constexpr auto kArmed = static_cast<std::uint8_t>(runtime::LoopState::kArmed);

// The columns the checks need, for every row of every file, in order.
struct Rows {
  std::vector<std::int64_t> cycle{};
  std::vector<std::uint8_t> state{};
  std::vector<double> command{};
  std::vector<double> setpoint{};
  std::vector<double> s_hat{};
  std::vector<std::uint32_t> faults{};
  std::vector<std::uint32_t> driver_status{};

  [[nodiscard]] std::size_t size() const noexcept { return cycle.size(); }
  // The row of a cycle (cycles are increasing once checked).
  [[nodiscard]] std::optional<std::size_t> row_of(std::int64_t c) const {
    const auto it = std::lower_bound(cycle.begin(), cycle.end(), c);
    if (it == cycle.end() || *it != c) return std::nullopt;
    return static_cast<std::size_t>(it - cycle.begin());
  }
};

void append(Rows& rows, const io::Recording& r) {
  const auto add = [&r](std::string_view name, auto& out) {
    using T = typename std::remove_reference_t<decltype(out)>::value_type;
    for (const double v : r.column(name))
      out.push_back(static_cast<T>(v));
  };
  add("cycle", rows.cycle);
  add("state", rows.state);
  add("command", rows.command);
  add("setpoint", rows.setpoint);
  add("S_hat", rows.s_hat);
  add("faults", rows.faults);
  add("driver_status", rows.driver_status);
}

std::string fault_names(std::uint32_t bits) {
  std::string text;
  for (std::size_t i = 0; i < runtime::kFaultCount; ++i) {
    if ((bits & (1U << i)) == 0U) continue;
    text += text.empty() ? "" : "+";
    text += runtime::to_string(static_cast<runtime::Fault>(i));
  }
  return text.empty() ? "none" : text;
}

class Checker final {
 public:
  Checker(const Rows& rows, const RecordingExpectations& expect, RecordingReport& report)
      : rows_(rows), expect_(expect), report_(report) {}

  void contiguity() {
    report_.rows = static_cast<std::int64_t>(rows_.size());
    if (rows_.size() == 0) return fail("no rows recorded");
    report_.first_cycle = rows_.cycle.front();
    report_.last_cycle = rows_.cycle.back();
    if (report_.first_cycle != 1) {
      fail("the recording starts at cycle " + std::to_string(report_.first_cycle) + ", not 1");
    }
    for (std::size_t i = 1; i < rows_.size(); ++i) {
      const std::int64_t step = rows_.cycle[i] - rows_.cycle[i - 1];
      if (step == 1) continue;
      if (step < 1) {
        fail("cycle " + std::to_string(rows_.cycle[i]) + " after " +
             std::to_string(rows_.cycle[i - 1]));
      } else {
        report_.missing_cycles += step - 1;
        fail("cycles " + std::to_string(rows_.cycle[i - 1] + 1) + ".." +
             std::to_string(rows_.cycle[i] - 1) + " missing");
      }
    }
    if (expect_.last_cycle > 0 && report_.last_cycle != expect_.last_cycle) {
      fail("the recording ends at cycle " + std::to_string(report_.last_cycle) +
           ", the daemon stopped at " + std::to_string(expect_.last_cycle));
    }
  }

  // Every planned item; `next` is the cycle the following item starts (its deadline to re-arm).
  void item(const PlannedFault& p, std::int64_t next) {
    EpisodeFigures e;
    e.name = p.name;
    e.rearm_cycles = -1;
    const std::optional<std::size_t> start = rows_.row_of(p.start_cycle);
    if (!start || *start == 0) {
      return fail(p.name + ": cycle " + std::to_string(p.start_cycle) + " not recorded");
    }
    std::size_t onset = *start;
    if (p.source == Source::kWatchdog) {
      std::optional<std::size_t> w;
      for (std::size_t i = onset; i < rows_.size() && rows_.cycle[i] < next; ++i) {
        if ((rows_.faults[i] & ~rows_.faults[i - 1] & p.loop_fault) != 0U) {
          w = i;
          break;
        }
      }
      if (!w) {
        return fail(p.name + " from cycle " + std::to_string(p.start_cycle) +
                    ": the watchdog never tripped");
      }
      onset = *w;
      watchdog_onsets_.push_back(rows_.cycle[onset]);
      hold_before_watchdog(p, onset);
    } else {
      const std::size_t i = onset;
      if ((rows_.driver_status[i] & p.plant_bit) == 0U) {
        fail(p.name + ": the plant's status bit is not in cycle " + std::to_string(p.start_cycle) +
             " (driver_status " + std::to_string(rows_.driver_status[i]) + ")");
      }
      if ((rows_.driver_status[i - 1] & p.plant_bit) != 0U) {
        fail(p.name + ": the plant's status bit is there before cycle " +
             std::to_string(p.start_cycle));
      }
    }
    e.onset_cycle = rows_.cycle[onset];
    e.armed_before = rows_.state[onset - 1] == kArmed;
    if (p.loop_fault == 0U) {  // not a fault: nothing may latch (checked with every rising bit)
      report_.episodes.push_back(e);
      return;
    }
    if (rows_.state[onset] != kFaulted || rows_.command[onset] != expect_.safe_value ||
        (rows_.faults[onset] & p.loop_fault) == 0U) {
      fail(p.name + " at cycle " + std::to_string(e.onset_cycle) + ": state " +
           std::to_string(rows_.state[onset]) + ", command " +
           std::to_string(rows_.command[onset]) + ", faults " + fault_names(rows_.faults[onset]) +
           " in the cycle of its cause (want faulted, the safe value, " +
           fault_names(p.loop_fault) + ")");
    }
    std::size_t i = onset;
    for (; i < rows_.size() && rows_.state[i] == kFaulted; ++i) {
      if (rows_.command[i] != expect_.safe_value || (rows_.faults[i] & p.loop_fault) == 0U) {
        fail(p.name + ": at cycle " + std::to_string(rows_.cycle[i]) + " while faulted, command " +
             std::to_string(rows_.command[i]) + " faults " + fault_names(rows_.faults[i]));
        break;
      }
    }
    if (i == rows_.size()) {
      return fail(p.name + " at cycle " + std::to_string(e.onset_cycle) + ": never reset");
    }
    e.latched_cycles = rows_.cycle[i] - e.onset_cycle;
    while (i < rows_.size() && rows_.state[i] != kArmed && rows_.cycle[i] < next)
      ++i;
    if (i == rows_.size() || rows_.cycle[i] >= next) {
      report_.episodes.push_back(e);
      return fail(p.name + " at cycle " + std::to_string(e.onset_cycle) +
                  ": not armed again before cycle " + std::to_string(next));
    }
    e.rearm_cycles = rows_.cycle[i] - e.onset_cycle;
    e.tracking_rms = tracking(i, next);
    if (e.tracking_rms < 0.0) {
      fail(p.name + ": re-armed at cycle " + std::to_string(rows_.cycle[i]) +
           " but not armed long enough to score the tracking");
    } else if (e.tracking_rms > expect_.tracking_rms_max) {
      fail(p.name + ": after the re-arm at cycle " + std::to_string(rows_.cycle[i]) +
           " S_hat tracks the setpoint with RMS " + std::to_string(e.tracking_rms) + " > " +
           std::to_string(expect_.tracking_rms_max));
    }
    report_.episodes.push_back(e);
  }

  // Every fault bit that rises must be a planned item's, the watchdog's, or an overrun the
  // timing statistics show.
  void rising_bits(const std::vector<PlannedFault>& plan) {
    if (rows_.size() > 0 && rows_.faults[0] != runtime::bit(runtime::Fault::kPowerUp)) {
      fail("the first row's faults are " + fault_names(rows_.faults[0]) + ", not power_up");
    }
    // SIGTERM's disarm steps the command to the safe value; the mount's resonance then rings
    // the stress, which at 20 kHz was seen to pass the stress range in the stop's last cycles
    // (estimate_out_of_range after the final disarm: the estimate doing its job, not a fault of
    // the run).
    std::size_t stopped = rows_.size();
    while (stopped > 0 && rows_.state[stopped - 1] != kArmed)
      --stopped;
    for (std::size_t i = 1; i < rows_.size(); ++i) {
      const std::uint32_t rose = rows_.faults[i] & ~rows_.faults[i - 1];
      if (rose == 0U) continue;
      const std::int64_t c = rows_.cycle[i];
      for (std::size_t b = 0; b < runtime::kFaultCount; ++b) {
        const std::uint32_t bit = 1U << b;
        if ((rose & bit) == 0U || explained(plan, bit, c)) continue;
        if (i >= stopped && bit == runtime::bit(runtime::Fault::kEstimateOutOfRange) &&
            rows_.size() - i < 400) {
          continue;
        }
        fail("unexplained fault " + fault_names(bit) + " at cycle " + std::to_string(c) +
             " (driver_status " + std::to_string(rows_.driver_status[i]) + ")");
      }
    }
  }

 private:
  void fail(const std::string& what) {
    if (report_.failures.size() < 40) report_.failures.push_back(what);
  }

  bool explained(const std::vector<PlannedFault>& plan, std::uint32_t bit, std::int64_t c) {
    if (bit == runtime::bit(runtime::Fault::kOverrun)) {
      ++report_.overrun_faults;
      return expect_.overruns_shown;
    }
    if (bit == runtime::bit(runtime::Fault::kWatchdog)) {
      return std::find(watchdog_onsets_.begin(), watchdog_onsets_.end(), c) !=
             watchdog_onsets_.end();
    }
    return std::any_of(plan.begin(), plan.end(), [&](const PlannedFault& p) {
      return p.source == Source::kPlant && p.loop_fault == bit && c >= p.start_cycle &&
             c < p.start_cycle + p.cycles;
    });
  }

  // The watchdog trips watchdog_s after the wave stopped: the armed rows holding the last
  // setpoint before the onset are that many cycles (and at most a few more).
  void hold_before_watchdog(const PlannedFault& p, std::size_t onset) {
    const double held = rows_.setpoint[onset - 1];
    std::size_t h = onset - 1;
    while (h > 0 && rows_.state[h - 1] == kArmed && rows_.setpoint[h - 1] == held)
      --h;
    const auto hold = static_cast<std::int64_t>(onset - h);
    const std::int64_t want = std::llround(expect_.watchdog_s * expect_.rate_hz);
    if (hold < want || hold > want + 3) {
      fail(p.name + " at cycle " + std::to_string(rows_.cycle[onset]) + ": tripped after " +
           std::to_string(hold) + " cycles of held setpoint, want " + std::to_string(want) +
           " (+3)");
    }
  }

  // RMS of S_hat - setpoint from `settle_s` after the arm at row `armed` for `score_s` (or to
  // the next item); -1 when fewer than 0.2 s of armed rows are in the window.
  double tracking(std::size_t armed, std::int64_t next) const {
    const std::int64_t settle = std::llround(expect_.settle_s * expect_.rate_hz);
    const std::int64_t score = std::llround(expect_.score_s * expect_.rate_hz);
    const std::int64_t from = rows_.cycle[armed] + settle;
    const std::int64_t to = std::min<std::int64_t>(from + score, next);
    double sum = 0.0;
    std::int64_t n = 0;
    for (std::size_t i = armed; i < rows_.size() && rows_.cycle[i] < to; ++i) {
      if (rows_.cycle[i] < from) continue;
      if (rows_.state[i] != kArmed) break;
      const double e = rows_.s_hat[i] - rows_.setpoint[i];
      sum += e * e;
      ++n;
    }
    if (static_cast<double>(n) < 0.2 * expect_.rate_hz) return -1.0;
    return std::sqrt(sum / static_cast<double>(n));
  }

  const Rows& rows_;
  const RecordingExpectations& expect_;
  RecordingReport& report_;
  std::vector<std::int64_t> watchdog_onsets_{};
};

}  // namespace

RecordingReport check_recordings(const std::filesystem::path& directory,
                                 const std::vector<PlannedFault>& plan,
                                 const RecordingExpectations& expect) {
  RecordingReport report;
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(directory)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("selfsensed-", 0) == 0 && entry.path().extension() == ".csv") {
      files.push_back(entry.path());
    }
  }
  std::sort(files.begin(), files.end());
  report.files = files.size();
  Rows rows;
  io::ReadOptions options;
  options.required = {"t",        "E",     "cycle",  "state",        "command",
                      "setpoint", "S_hat", "faults", "driver_status"};
  for (const std::filesystem::path& file : files) {
    try {
      append(rows, io::read_recording_csv(file, options));
    } catch (const std::exception& e) {
      report.failures.push_back(std::string("unreadable recording: ") + e.what());
    }
  }
  Checker check(rows, expect, report);
  check.contiguity();
  if (!report.failures.empty()) return report;
  for (std::size_t k = 0; k < plan.size(); ++k) {
    const std::int64_t next = k + 1 < plan.size() ? plan[k + 1].start_cycle : report.last_cycle + 1;
    check.item(plan[k], next);
  }
  check.rising_bits(plan);
  return report;
}

}  // namespace selfsense::soak
