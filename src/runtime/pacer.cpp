#include "selfsense/runtime/pacer.hpp"

#include <algorithm>
#include <cassert>

#include "selfsense/runtime/monotonic.hpp"

namespace selfsense::runtime {

std::int64_t SteadyClock::now_ns() noexcept {
  return monotonic_ns();
}

void SteadyClock::sleep_until_ns(std::int64_t t) noexcept {
  sleep_until(t);
}

Pacer::Pacer(Clock& clock, std::int64_t period_ns) noexcept
    : Pacer(clock, period_ns, period_ns / 10) {}

Pacer::Pacer(Clock& clock, std::int64_t period_ns, std::int64_t late_wakeup_ns) noexcept
    : clock_(&clock), period_ns_(period_ns), late_wakeup_ns_(late_wakeup_ns) {
  assert(period_ns > 0);
}

void Pacer::start() noexcept {
  start_ns_ = clock_->now_ns();
  cycle_ = 0;
  stats_ = PacerStats{};
}

Pacer::Tick Pacer::wait() noexcept {
  ++cycle_;
  Tick tick;
  const std::int64_t now = clock_->now_ns();
  std::int64_t deadline = start_ns_ + cycle_ * period_ns_;
  if (now > deadline) {
    // The next deadline still ahead: skip the missed ones rather than burst, and count each.
    const std::int64_t next = (now - start_ns_) / period_ns_ + 1;
    tick.overrun = true;
    tick.late_ns = now - deadline;
    tick.missed = next - cycle_;
    stats_.overruns += tick.missed;
    stats_.missed_periods += tick.missed;
    ++stats_.late_cycles;
    stats_.last_overrun_cycle = cycle_;
    stats_.worst_late_ns = std::max(stats_.worst_late_ns, tick.late_ns);
    cycle_ = next;
    deadline = start_ns_ + cycle_ * period_ns_;
  }
  clock_->sleep_until_ns(deadline);
  tick.wake_latency_ns = std::max<std::int64_t>(clock_->now_ns() - deadline, 0);
  stats_.wake_latency.record(tick.wake_latency_ns);
  if (tick.wake_latency_ns > late_wakeup_ns_) ++stats_.late_wakeups;
  ++stats_.cycles;
  tick.cycle = cycle_;
  tick.deadline_ns = deadline;
  return tick;
}

}  // namespace selfsense::runtime
