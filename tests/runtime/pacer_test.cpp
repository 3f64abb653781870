#include "selfsense/runtime/pacer.hpp"

#include <gtest/gtest.h>

#include "support/allocation_counter.hpp"

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
  EXPECT_EQ(pacer.missed_periods(), 0);
  EXPECT_EQ(pacer.stats().cycles, 1000);
  EXPECT_EQ(pacer.stats().late_wakeups, 0);
  EXPECT_EQ(pacer.stats().wake_latency.max_ns(), 0);
}

TEST(Pacer, ThreeMissedDeadlinesAreThreeOverrunsAndThreeSkippedPeriods) {
  SimulatedClock clock;
  Pacer pacer(clock, kPeriod);
  pacer.start();
  clock.advance_ns(20'000);
  EXPECT_EQ(pacer.wait().cycle, 1);
  clock.advance_ns(350'000);  // woke at 100 us, work until 450 us: past deadlines 200, 300, 400
  const Pacer::Tick late = pacer.wait();
  EXPECT_TRUE(late.overrun);
  EXPECT_EQ(late.missed, 3);
  EXPECT_EQ(late.late_ns, 250'000);  // now 450 us, deadline of cycle 2 was 200 us
  EXPECT_EQ(late.cycle, 5);          // next deadline in the future: 500 us, no burst
  EXPECT_EQ(clock.now_ns(), 500'000);
  clock.advance_ns(10'000);
  const Pacer::Tick next = pacer.wait();
  EXPECT_FALSE(next.overrun);
  EXPECT_EQ(next.missed, 0);
  EXPECT_EQ(next.cycle, 6);
  const PacerStats& s = pacer.stats();
  EXPECT_EQ(s.cycles, 3);
  EXPECT_EQ(s.overruns, 3);
  EXPECT_EQ(s.missed_periods, 3);
  EXPECT_EQ(s.late_cycles, 1);
  EXPECT_EQ(s.worst_late_ns, 250'000);
  EXPECT_EQ(s.last_overrun_cycle, 2);
}

TEST(Pacer, OverrunEpisodesAddUpDeadlineByDeadline) {
  SimulatedClock clock;
  Pacer pacer(clock, kPeriod);
  pacer.start();
  // Work per cycle [us]: on time, one deadline missed (by 1 ns), on time, two missed, exactly
  // at the deadline (not missed), three missed.
  const std::int64_t work[] = {50'000, 100'001, 10'000, 250'000, 100'000, 399'999};
  const std::int64_t missed[] = {0, 1, 0, 2, 0, 3};
  std::int64_t total = 0;
  for (int k = 0; k < 6; ++k) {
    clock.advance_ns(work[k]);
    const Pacer::Tick tick = pacer.wait();
    EXPECT_EQ(tick.missed, missed[k]) << "cycle " << k;
    EXPECT_EQ(tick.overrun, missed[k] > 0) << "cycle " << k;
    EXPECT_EQ(tick.deadline_ns, clock.now_ns()) << "cycle " << k;
    total += missed[k];
  }
  EXPECT_EQ(total, 6);
  EXPECT_EQ(pacer.overruns(), 6);
  EXPECT_EQ(pacer.missed_periods(), 6);
  EXPECT_EQ(pacer.stats().late_cycles, 3);
  EXPECT_EQ(pacer.stats().cycles, 6);
  EXPECT_EQ(pacer.stats().worst_late_ns, 299'999);  // the last: entered 299.999 us late
  // 6 cycles returned and 6 periods skipped: the last deadline is cycle 12.
  EXPECT_EQ(clock.now_ns(), 12 * kPeriod);
}

TEST(Pacer, WakeUpLatencyIsHistogrammedAndLateWakeUpsAreCounted) {
  SimulatedClock clock;
  Pacer pacer(clock, kPeriod);  // late wake-up: more than 10 us after the deadline
  pacer.start();
  for (int k = 0; k < 1000; ++k) {
    // 990 wake-ups 3 ns late, 9 at 5 us, one at 60 us: only that one is a late wake-up.
    clock.set_wake_latency_ns(k == 500 ? 60'000 : (k % 100 == 7 && k < 900 ? 5'000 : 3));
    clock.advance_ns(10'000);
    const Pacer::Tick tick = pacer.wait();
    ASSERT_FALSE(tick.overrun);
    ASSERT_EQ(tick.wake_latency_ns, k == 500 ? 60'000 : (k % 100 == 7 && k < 900 ? 5'000 : 3));
  }
  const PacerStats& s = pacer.stats();
  EXPECT_EQ(s.late_wakeups, 1);
  EXPECT_EQ(s.overruns, 0);
  EXPECT_EQ(s.wake_latency.count(), 1000);
  EXPECT_EQ(s.wake_latency.sum_ns(), 990 * 3 + 9 * 5'000 + 60'000);
  EXPECT_EQ(s.wake_latency.percentile_ns(0.5), 3);       // bucket [2, 3]
  EXPECT_EQ(s.wake_latency.percentile_ns(0.99), 3);      // rank 990
  EXPECT_EQ(s.wake_latency.percentile_ns(0.999), 8191);  // rank 999: bucket [4096, 8191]
  EXPECT_EQ(s.wake_latency.max_ns(), 60'000);
  EXPECT_EQ(s.wake_latency.percentile_ns(1.0), 60'000);
}

TEST(Pacer, AWakeUpLaterThanAPeriodMissesTheNextDeadline) {
  SimulatedClock clock;
  Pacer pacer(clock, kPeriod, 20'000);
  pacer.start();
  clock.set_wake_latency_ns(150'000);  // the sleep to 100 us returns at 250 us
  clock.advance_ns(10'000);
  EXPECT_EQ(pacer.wait().wake_latency_ns, 150'000);
  clock.set_wake_latency_ns(0);
  clock.advance_ns(10'000);  // 260 us: the deadline at 200 us has passed
  const Pacer::Tick tick = pacer.wait();
  EXPECT_EQ(tick.missed, 1);
  EXPECT_EQ(tick.cycle, 3);
  EXPECT_EQ(pacer.stats().late_wakeups, 1);
  EXPECT_EQ(pacer.overruns(), 1);
}

TEST(Pacer, StartClearsTheStatistics) {
  SimulatedClock clock;
  Pacer pacer(clock, kPeriod);
  pacer.start();
  clock.advance_ns(250'000);
  static_cast<void>(pacer.wait());
  ASSERT_EQ(pacer.overruns(), 2);
  pacer.start();
  EXPECT_EQ(pacer.overruns(), 0);
  EXPECT_EQ(pacer.stats().cycles, 0);
  EXPECT_EQ(pacer.stats().wake_latency.count(), 0);
  EXPECT_EQ(pacer.last_overrun_cycle(), -1);
}

TEST(Pacer, SteadyClockSleepsToAnAbsoluteDeadline) {
  SteadyClock clock;
  const std::int64_t t0 = clock.now_ns();
  clock.sleep_until_ns(t0 + 2'000'000);
  EXPECT_GE(clock.now_ns(), t0 + 2'000'000);
  clock.sleep_until_ns(t0);  // in the past: returns at once
}

TEST(Pacer, WaitOnTheSteadyClockNeitherAllocatesNorLocks) {
  SteadyClock clock;
  Pacer pacer(clock, 50'000);  // 20 kHz
  pacer.start();
  test::AllocationCounter counter;
  for (int k = 0; k < 200; ++k)
    static_cast<void>(pacer.wait());
  EXPECT_EQ(counter.count(), 0U);
  EXPECT_EQ(counter.deallocations(), 0U);
  EXPECT_EQ(counter.locks(), 0U);
  EXPECT_EQ(pacer.stats().cycles, 200);
}

}  // namespace
}  // namespace selfsense::runtime
