#include "selfsense/runtime/supervisor.hpp"

#include <algorithm>
#include <array>
#include <limits>

#include "selfsense/base/check.hpp"

namespace selfsense::runtime {

std::string_view to_string(Fault f) noexcept {
  constexpr std::array<std::string_view, kFaultCount> kNames{
      "power_up",         "driver_error",       "driver_timeout",        "stale_sample",
      "input_not_finite", "input_out_of_range", "estimate_out_of_range", "reconstruction",
      "overrun",          "watchdog",           "amplifier_fault",       "health"};
  const auto i = static_cast<std::size_t>(f);
  return i < kNames.size() ? kNames[i] : std::string_view("unknown");
}

std::string_view cause_of(Fault f) noexcept {
  constexpr std::array<std::string_view, kFaultCount> kCauses{
      "started: a reset is required before arming",
      "the driver reported an error, bad data or a device fault",
      "no sample in time, or the device is disconnected",
      "the sample repeats the last one (stuck converter or missed data-ready)",
      "E or D is not finite",
      "E or D outside the model's range",
      "T_hat or S_hat outside safety.stress_range_pa or safety.strain_range",
      "the model found no unique solution",
      "the loop missed its deadlines beyond safety.overrun",
      "armed on socket setpoints and none arrived within safety.watchdog_s",
      "the amplifier's fault line",
      "a health alarm beyond its band (health.fault)"};
  const auto i = static_cast<std::size_t>(f);
  return i < kCauses.size() ? kCauses[i] : std::string_view("unknown");
}

bool OverrunPolicy::is_valid(std::string* why) const {
  using base::check::require;
  return require(consecutive >= 1, "safety.overrun.consecutive", consecutive, "must be >= 1",
                 why) &&
         require(within_count <= 64, "safety.overrun.within_count", within_count,
                 "must be within [0, 64]", why) &&
         require(window >= within_count, "safety.overrun.window_cycles", window,
                 "must be >= within_count", why);
}

Supervisor::Supervisor(const OverrunPolicy& policy) noexcept : policy_(policy) {
  recent_.fill(-1);
  report(Fault::kPowerUp, 0);
}

void Supervisor::report(Fault f, std::int64_t cycle) noexcept {
  FaultRecord& r = records_[static_cast<std::size_t>(f)];
  ++r.count;
  if (r.first_cycle < 0 || (latched_ & bit(f)) == 0) r.first_cycle = cycle;
  r.last_cycle = cycle;
  latched_ |= bit(f);
  state_ = LoopState::kFaulted;
}

void Supervisor::note_cycle(bool overrun, std::int64_t cycle, std::int64_t missed) noexcept {
  if (!overrun) {
    consecutive_ = 0;
    return;
  }
  const std::int64_t in_row =
      static_cast<std::int64_t>(consecutive_) + 1 + std::max<std::int64_t>(missed, 0);
  consecutive_ = static_cast<std::uint32_t>(
      std::min<std::int64_t>(in_row, std::numeric_limits<std::uint32_t>::max()));
  recent_[recent_next_] = cycle;
  recent_next_ = (recent_next_ + 1) % recent_.size();
  // The within_count-th most recent overrun, still inside the window? (within_count 0: off)
  bool dense = false;
  if (policy_.within_count > 0) {
    const std::size_t back =
        (recent_next_ + recent_.size() - policy_.within_count) % recent_.size();
    const std::int64_t oldest = recent_[back];
    dense = oldest >= 0 && cycle - oldest < static_cast<std::int64_t>(policy_.window);
  }
  if (consecutive_ >= policy_.consecutive || dense) report(Fault::kOverrun, cycle);
}

bool Supervisor::reset() noexcept {
  if (state_ != LoopState::kFaulted) return false;
  latched_ = 0;
  consecutive_ = 0;
  recent_.fill(-1);
  state_ = LoopState::kReady;
  return true;
}

bool Supervisor::arm() noexcept {
  if (state_ != LoopState::kReady) return false;
  state_ = LoopState::kArmed;
  return true;
}

bool Supervisor::disarm() noexcept {
  if (state_ != LoopState::kArmed) return false;
  state_ = LoopState::kReady;
  return true;
}

}  // namespace selfsense::runtime
