#include "selfsense/runtime/pacer.hpp"

#include <gtest/gtest.h>

namespace selfsense::runtime {
namespace {

constexpr std::int64_t kPeriod = 100'000;  // 10 kHz

TEST(Pacer, DeadlinesAreAbsoluteSoWorkTimeDoesNotDrift) {
  SimulatedClock clock;
  clock.advance_ns(5'000'000);
  Pacer pacer(clock, kPeriod);
  pacer.start();
  for (int k = 1; k <= 1000; ++k) {
    clock.advance_ns(30'000 + (k % 7) * 5'000);  // varying work, always within the period
    const Pacer::Tick tick = pacer.wait();
    ASSERT_FALSE(tick.overrun);
    ASSERT_EQ(tick.cycle, k);
    ASSERT_EQ(clock.now_ns(), 5'000'000 + k * kPeriod);
  }
  EXPECT_EQ(pacer.overruns(), 0);
}

TEST(Pacer, OverrunsAreCountedAndSkipAheadWithoutABurst) {
  SimulatedClock clock;
  Pacer pacer(clock, kPeriod);
  pacer.start();
  clock.advance_ns(20'000);
  EXPECT_EQ(pacer.wait().cycle, 1);
  clock.advance_ns(350'000);  // woke at 100 us, work until 450 us: past cycles 2 to 4
  const Pacer::Tick late = pacer.wait();
  EXPECT_TRUE(late.overrun);
  EXPECT_EQ(late.late_ns, 250'000);  // now 450 us, deadline of cycle 2 was 200 us
  EXPECT_EQ(late.cycle, 5);          // next deadline in the future: 500 us
  EXPECT_EQ(clock.now_ns(), 500'000);
  clock.advance_ns(10'000);
  const Pacer::Tick next = pacer.wait();
  EXPECT_FALSE(next.overrun);
  EXPECT_EQ(next.cycle, 6);
  EXPECT_EQ(pacer.overruns(), 1);
  EXPECT_EQ(pacer.worst_late_ns(), 250'000);
  EXPECT_EQ(pacer.last_overrun_cycle(), 2);
}

TEST(Pacer, SteadyClockSleepsToAnAbsoluteDeadline) {
  SteadyClock clock;
  const std::int64_t t0 = clock.now_ns();
  clock.sleep_until_ns(t0 + 2'000'000);
  EXPECT_GE(clock.now_ns(), t0 + 2'000'000);
  clock.sleep_until_ns(t0);  // in the past: returns at once
}

}  // namespace
}  // namespace selfsense::runtime
