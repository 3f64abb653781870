#include "selfsense/runtime/monotonic.hpp"

#include <cerrno>
#include <ctime>

namespace selfsense::runtime {
namespace {

constexpr std::int64_t kNsPerS = 1'000'000'000;

}  // namespace

std::int64_t monotonic_ns() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * kNsPerS + ts.tv_nsec;
}

Wake sleep_once_until(std::int64_t deadline_ns) noexcept {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(deadline_ns / kNsPerS);
  ts.tv_nsec = static_cast<long>(deadline_ns % kNsPerS);
  switch (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr)) {
    case 0:
      return Wake::kDeadline;
    case EINTR:
      return Wake::kInterrupted;
    default:
      return Wake::kInvalid;
  }
}

void sleep_until(std::int64_t deadline_ns) noexcept {
  while (sleep_once_until(deadline_ns) == Wake::kInterrupted) {
  }
}

}  // namespace selfsense::runtime
