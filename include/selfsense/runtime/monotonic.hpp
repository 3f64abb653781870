// The monotonic clock and sleeping to an absolute deadline on it
// (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME)): the one pacing primitive of every loop
// that paces itself (the Pacer, the Modbus driver's bus thread, the simulated CAN node). An
// absolute deadline does not drift: the work between sleeps is not added to the period.
//
// Here and not in base: base is the pure math's ground floor, which must not see clocks
// (tests/layering/check_layering.sh); every paced loop already depends on runtime.
// All real-time safe: no allocation, no lock, no exception.
#pragma once

#include <cstdint>

namespace selfsense::runtime {

// CLOCK_MONOTONIC in ns.
[[nodiscard]] std::int64_t monotonic_ns() noexcept;

enum class Wake {
  kDeadline,     // the deadline has passed
  kInterrupted,  // a signal handler ran first (the caller looks at its stop flag)
  kInvalid,      // a negative deadline
};

// One sleep until deadline_ns, ended early by a signal handler.
[[nodiscard]] Wake sleep_once_until(std::int64_t deadline_ns) noexcept;

// Sleeps until deadline_ns, sleeping again after each signal handler.
void sleep_until(std::int64_t deadline_ns) noexcept;

}  // namespace selfsense::runtime
