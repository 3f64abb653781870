// The one absolute-deadline sleep (runtime/monotonic.hpp) that the Pacer, the Modbus driver's
// bus thread and the simulated CAN node pace with.
#include "selfsense/runtime/monotonic.hpp"

#include <gtest/gtest.h>

#include <cstdint>

namespace selfsense::runtime {
namespace {

TEST(Monotonic, SleepOnceReturnsAtTheDeadline) {
  const std::int64_t t0 = monotonic_ns();
  EXPECT_EQ(sleep_once_until(t0 + 1'000'000), Wake::kDeadline);
  EXPECT_GE(monotonic_ns(), t0 + 1'000'000);
  EXPECT_EQ(sleep_once_until(t0), Wake::kDeadline);  // in the past: at once
}

TEST(Monotonic, ANegativeDeadlineIsInvalidNotASleep) {
  EXPECT_EQ(sleep_once_until(-1), Wake::kInvalid);
}

TEST(Monotonic, SleepUntilReachesTheDeadline) {
  const std::int64_t t0 = monotonic_ns();
  sleep_until(t0 + 2'000'000);
  EXPECT_GE(monotonic_ns(), t0 + 2'000'000);
}

}  // namespace
}  // namespace selfsense::runtime
