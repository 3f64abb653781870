// What starts a cycle when the hardware, not a timer, paces the loop: a converter's data-ready
// edge (an ADC on the loop's SPI bus sampling at the loop's rate). A driver that can pace offers
// one (Driver::cycle_trigger()); LoopRunner then waits on it instead of on its Pacer, so that the
// cycle follows the converter's crystal and never drifts against it.
//
// wait() runs on the real-time thread and is its pacing sleep: it blocks in one system call (the
// GPIO character device's poll) until the edge or the timeout, allocates nothing and never
// throws. kTimeout: no edge in time (the loop still runs its cycle, whose read() then reports
// the missing sample); kError: the line cannot be waited on.
#pragma once

#include <cstdint>

namespace selfsense::runtime {

class CycleTrigger {
 public:
  enum class Result : std::uint8_t { kReady, kTimeout, kError };

  CycleTrigger() = default;
  CycleTrigger(const CycleTrigger&) = delete;
  CycleTrigger& operator=(const CycleTrigger&) = delete;
  CycleTrigger(CycleTrigger&&) = delete;
  CycleTrigger& operator=(CycleTrigger&&) = delete;
  virtual ~CycleTrigger() = default;

  // Blocks until the next trigger or timeout_ns have passed.
  virtual Result wait(std::int64_t timeout_ns) noexcept = 0;
  // When the trigger that ended the last kReady wait fired (the data-ready edge's kernel time
  // stamp), on the clock of the thread that waits (CLOCK_MONOTONIC on the target); -1 when the
  // trigger does not know. LoopRunner measures its wake-up latency from it.
  [[nodiscard]] virtual std::int64_t fired_ns() const noexcept { return -1; }
};

}  // namespace selfsense::runtime
