// The real-time thread: real-time set-up once, then the loop paced to absolute deadlines
// (Pacer on CLOCK_MONOTONIC), or, when the driver offers a CycleTrigger (an ADC's data-ready
// edge), to the trigger: each cycle starts when it fires, and a trigger that does not fire within
// two periods counts as an overrun and the cycle runs anyway (its read() reports the missing
// sample, the supervisor faults). Each cycle's execution time and wake-up latency are measured and
// published with the loop's status; paced by a trigger, the wake-up latency runs from the
// trigger's time stamp (CycleTrigger::fired_ns(), the data-ready edge) to the wake-up, for the
// triggers that give one (else it stays 0). progress() counts finished cycles: the daemon pings the
// systemd watchdog only while it advances, so a stalled loop gets the service restarted.
//
//   start()  spawns the thread (not real-time); stop() asks it to finish its cycle and joins.
// Inside the thread nothing allocates, locks or does I/O after the set-up.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>

#include "selfsense/runtime/cycle_trigger.hpp"
#include "selfsense/runtime/loop.hpp"
#include "selfsense/runtime/pacer.hpp"
#include "selfsense/runtime/rt_setup.hpp"

namespace selfsense::runtime {

class LoopRunner final {
 public:
  // trigger: null for the pacer; otherwise the driver's (valid while the runner runs).
  LoopRunner(Loop& loop, Clock& clock, std::int64_t period_ns, const RtOptions& rt,
             CycleTrigger* trigger = nullptr);
  LoopRunner(const LoopRunner&) = delete;
  LoopRunner& operator=(const LoopRunner&) = delete;
  LoopRunner(LoopRunner&&) = delete;
  LoopRunner& operator=(LoopRunner&&) = delete;
  ~LoopRunner();

  // Starts the thread and waits for its real-time set-up; the result says what failed.
  RtSetupResult start();
  void stop();
  [[nodiscard]] std::uint64_t progress() const noexcept {
    return progress_.load(std::memory_order_relaxed);
  }
  // Test hook: the loop thread stops cycling (simulates a stalled loop) without exiting.
  void stall(bool on) noexcept { stall_.store(on, std::memory_order_relaxed); }

 private:
  void run();
  // One wait for the trigger; false when the cycle starts late (timeout or line error).
  bool wait_trigger() noexcept;

  Loop* loop_;
  Clock* clock_;
  std::int64_t period_ns_;
  RtOptions rt_;
  CycleTrigger* trigger_;
  std::thread thread_{};
  std::atomic<bool> stop_{false};
  std::atomic<bool> stall_{false};
  std::atomic<std::uint64_t> progress_{0};
  std::mutex setup_mutex_{};  // hands the set-up result to start(); never used by the cycle
  bool setup_done_{false};
  RtSetupResult setup_{};
  std::condition_variable setup_cv_{};
};

}  // namespace selfsense::runtime
