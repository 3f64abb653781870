// Fixed-rate pacing to absolute deadlines: the cycle of the daemon and of the paced plant.
//
//   deadline[k + 1] = deadline[k] + period      (absolute: no drift from the work's duration)
// wait() sleeps until the next deadline. If the work ran past it (an overrun), the pacer counts
// it, remembers how late it was, and moves on to the next deadline still in the future instead
// of running a burst of catch-up cycles.
//
// The clock is an interface so that tests run in simulated time; SteadyClock sleeps with
// clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME). wait() is real-time safe: no allocation, no
// exceptions, no locks.
#pragma once

#include <cstdint>

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

// CLOCK_MONOTONIC with absolute sleeps (retried on EINTR).
class SteadyClock final : public Clock {
 public:
  [[nodiscard]] std::int64_t now_ns() noexcept override;
  void sleep_until_ns(std::int64_t t) noexcept override;
};

// Simulated time for tests: sleeping jumps to the deadline; advance() models work.
class SimulatedClock final : public Clock {
 public:
  [[nodiscard]] std::int64_t now_ns() noexcept override { return now_; }
  void sleep_until_ns(std::int64_t t) noexcept override {
    if (t > now_) now_ = t;
  }
  void advance_ns(std::int64_t dt) noexcept { now_ += dt; }

 private:
  std::int64_t now_{0};
};

class Pacer final {
 public:
  struct Tick {
    std::int64_t cycle{0};        // index of the deadline this wait returned at
    std::int64_t deadline_ns{0};  // that deadline
    std::int64_t late_ns{0};      // how far past the deadline the wait was entered (overrun)
    bool overrun{false};
  };

  // period_ns > 0 (asserted); the first deadline is one period after start().
  Pacer(Clock& clock, std::int64_t period_ns) noexcept;

  void start() noexcept;
  // Sleeps to the next deadline; on an overrun skips to the next one in the future.
  Tick wait() noexcept;

  [[nodiscard]] std::int64_t overruns() const noexcept { return overruns_; }
  [[nodiscard]] std::int64_t worst_late_ns() const noexcept { return worst_late_ns_; }
  [[nodiscard]] std::int64_t last_overrun_cycle() const noexcept { return last_overrun_cycle_; }

 private:
  Clock* clock_;
  std::int64_t period_ns_;
  std::int64_t start_ns_{0};
  std::int64_t cycle_{0};
  std::int64_t overruns_{0};
  std::int64_t worst_late_ns_{0};
  std::int64_t last_overrun_cycle_{-1};
};

}  // namespace selfsense::runtime
