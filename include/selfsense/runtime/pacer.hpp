// Fixed-rate pacing to absolute deadlines: the cycle of the daemon and of the paced plant.
//
//   deadline[k + 1] = deadline[k] + period      (absolute: no drift from the work's duration)
// wait() sleeps until the next deadline. If the work ran past it (an overrun), the pacer moves
// on to the next deadline still in the future instead of running a burst of catch-up cycles,
// and counts every deadline it passed: work from 100 us to 450 us in a 100 us period misses
// the deadlines at 200, 300 and 400 us, which is three overruns and three skipped periods, and
// the loop runs again at 500 us.
//
// After each sleep it reads the clock again: how long after its deadline the sleep returned is
// the wake-up latency (the scheduler's and the timer's share of the cycle), kept in a log2
// histogram from which p50, p99, p99.9 and max are read, and counted as a late wake-up when it
// exceeds a threshold.
//
// The clock is an interface so that tests run in simulated time; SteadyClock sleeps with
// clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME). wait(), stats() and the accessors are
// real-time safe: no allocation, no exceptions, no locks.
#pragma once

#include <cstdint>

#include "selfsense/runtime/latency_histogram.hpp"

namespace selfsense::runtime {

class Clock {
 public:
  Clock() = default;
  Clock(const Clock&) = delete;
  Clock& operator=(const Clock&) = delete;
  Clock(Clock&&) = delete;
  Clock& operator=(Clock&&) = delete;
  virtual ~Clock() = default;
  // Monotonic time [ns].
  [[nodiscard]] virtual std::int64_t now_ns() noexcept = 0;
  // Returns at or after t [ns] (at once if t is past).
  virtual void sleep_until_ns(std::int64_t t) noexcept = 0;
};

// CLOCK_MONOTONIC with absolute sleeps, retried after signals (runtime/monotonic.hpp).
class SteadyClock final : public Clock {
 public:
  [[nodiscard]] std::int64_t now_ns() noexcept override;
  void sleep_until_ns(std::int64_t t) noexcept override;
};

// Simulated time for tests: sleeping jumps to the deadline plus the wake-up latency set (none
// by default); advance() models work.
class SimulatedClock final : public Clock {
 public:
  [[nodiscard]] std::int64_t now_ns() noexcept override { return now_; }
  void sleep_until_ns(std::int64_t t) noexcept override {
    if (t > now_) now_ = t + wake_latency_;
  }
  void advance_ns(std::int64_t dt) noexcept { now_ += dt; }
  // How late every following sleep returns [ns].
  void set_wake_latency_ns(std::int64_t dt) noexcept { wake_latency_ = dt; }

 private:
  std::int64_t now_{0};
  std::int64_t wake_latency_{0};
};

// What the pacer saw since start().
struct PacerStats {
  std::int64_t cycles{0};          // waits that returned
  std::int64_t overruns{0};        // deadlines missed: each one the work ran past counts
  std::int64_t missed_periods{0};  // periods skipped without a cycle (the pacer never bursts,
                                   // so one per missed deadline)
  std::int64_t late_cycles{0};     // waits entered past their deadline (one per overrun episode)
  std::int64_t worst_late_ns{0};   // the latest a wait was entered after its deadline
  std::int64_t last_overrun_cycle{-1};  // first deadline the latest overrun missed
  std::int64_t late_wakeups{0};         // sleeps that returned > late_wakeup_ns after deadline
  LatencyHistogram wake_latency{};      // [ns] after the deadline each sleep returned
};

class Pacer final {
 public:
  struct Tick {
    std::int64_t cycle{0};            // index of the deadline this wait returned at
    std::int64_t deadline_ns{0};      // that deadline
    std::int64_t late_ns{0};          // how far past its deadline the wait was entered
    std::int64_t missed{0};           // deadlines missed by this overrun (0 when on time)
    std::int64_t wake_latency_ns{0};  // how long after the deadline the sleep returned
    bool overrun{false};
  };

  // period_ns > 0 (asserted); the first deadline is one period after start(). A wake-up
  // later than late_wakeup_ns after its deadline counts as late (default: a tenth of the
  // period).
  Pacer(Clock& clock, std::int64_t period_ns) noexcept;
  Pacer(Clock& clock, std::int64_t period_ns, std::int64_t late_wakeup_ns) noexcept;

  // Starts the deadlines from now and clears the statistics.
  void start() noexcept;
  // Sleeps to the next deadline; on an overrun skips to the next one in the future.
  Tick wait() noexcept;

  [[nodiscard]] const PacerStats& stats() const noexcept { return stats_; }
  [[nodiscard]] std::int64_t period_ns() const noexcept { return period_ns_; }
  [[nodiscard]] std::int64_t overruns() const noexcept { return stats_.overruns; }
  [[nodiscard]] std::int64_t missed_periods() const noexcept { return stats_.missed_periods; }
  [[nodiscard]] std::int64_t worst_late_ns() const noexcept { return stats_.worst_late_ns; }
  [[nodiscard]] std::int64_t last_overrun_cycle() const noexcept {
    return stats_.last_overrun_cycle;
  }

 private:
  Clock* clock_;
  std::int64_t period_ns_;
  std::int64_t late_wakeup_ns_;
  std::int64_t start_ns_{0};
  std::int64_t cycle_{0};
  PacerStats stats_{};
};

}  // namespace selfsense::runtime
