// Safety supervision of the loop: the state machine, latched faults and the overrun policy.
//
//   faulted --reset (no active cause)--> ready --arm--> armed
//      ^                                   |  <-disarm--  |
//      +---------- any fault, from any state -------------+
// The loop starts faulted (kPowerUp: nothing moves before an explicit reset). A fault latches:
// its bit stays set, with its count and the cycle it first and last occurred, until a reset
// while no cause is active. While faulted or ready the loop writes the safe output; a fault
// seen in cycle k makes cycle k's command the safe output (the loop asks safe_output() after
// reporting, before writing).
//
// Overrun policy: a fault after `consecutive` overruns in a row, or `within_count` overruns
// within the last `window` cycles (within_count 0: no such criterion, only `consecutive`). A
// stall counts every deadline it missed: one late cycle after k missed periods is k + 1 overruns
// in a row (the amplifier held its command that long).
// Real-time safe: every method is noexcept, allocation-free.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "selfsense/runtime/loop_sample.hpp"

namespace selfsense::runtime {

enum class Fault : std::uint8_t {
  kPowerUp = 0,         // started: reset required before arming
  kDriverError,         // the driver reported an error or device fault
  kDriverTimeout,       // no sample in time / disconnected
  kStaleSample,         // the sample repeats the last one
  kInputNotFinite,      // E or D NaN/Inf
  kInputOutOfRange,     // E or D outside the model's range (the model rejected the sample)
  kEstimateOutOfRange,  // T_hat or S_hat outside the configured physical range
  kReconstruction,      // the model reported no (unique) solution
  kOverrun,             // overrun policy tripped
  kWatchdog,            // armed with socket setpoints and none arrived within the timeout
  kAmplifierFault,      // the amplifier or its fault line
  kHealth,              // a health alarm with health.fault true (adaptation/health_alarms.hpp)
  kCount
};
inline constexpr std::size_t kFaultCount = static_cast<std::size_t>(Fault::kCount);

[[nodiscard]] std::string_view to_string(Fault f) noexcept;
// What a fault means, in a few words (status `fault_details.*.cause`).
[[nodiscard]] std::string_view cause_of(Fault f) noexcept;
[[nodiscard]] constexpr std::uint32_t bit(Fault f) noexcept {
  return 1U << static_cast<unsigned>(f);
}

struct OverrunPolicy {
  std::uint32_t consecutive{3};    // >= 1
  std::uint32_t within_count{10};  // 0 (off) .. 64
  std::uint32_t window{10000};     // cycles, >= within_count
  [[nodiscard]] bool is_valid(std::string* why) const;
  friend bool operator==(const OverrunPolicy&, const OverrunPolicy&) = default;
};

struct FaultRecord {
  std::uint64_t count{0};
  std::int64_t first_cycle{-1};
  std::int64_t last_cycle{-1};
};

class Supervisor final {
 public:
  explicit Supervisor(const OverrunPolicy& policy = {}) noexcept;

  [[nodiscard]] LoopState state() const noexcept { return state_; }
  [[nodiscard]] std::uint32_t latched() const noexcept { return latched_; }
  [[nodiscard]] const FaultRecord& record(Fault f) const noexcept {
    return records_[static_cast<std::size_t>(f)];
  }

  // A cause seen in this cycle: latches and moves to faulted.
  void report(Fault f, std::int64_t cycle) noexcept;
  // Overruns: feed every cycle whether it overran; trips kOverrun by the policy.
  // missed: deadlines that passed without a cycle before this late one (counted in a row).
  void note_cycle(bool overrun, std::int64_t cycle, std::int64_t missed = 0) noexcept;

  // Requests; false (nothing changes) when not allowed in the current state.
  bool reset() noexcept;   // faulted -> ready (clears the latched faults)
  bool arm() noexcept;     // ready -> armed
  bool disarm() noexcept;  // armed -> ready

  [[nodiscard]] bool armed() const noexcept { return state_ == LoopState::kArmed; }

 private:
  OverrunPolicy policy_{};
  LoopState state_{LoopState::kFaulted};
  std::uint32_t latched_{0};
  std::array<FaultRecord, kFaultCount> records_{};
  std::uint32_t consecutive_{0};
  std::array<std::int64_t, 64> recent_{};  // cycles of the last overruns (ring)
  std::size_t recent_next_{0};
};

}  // namespace selfsense::runtime
