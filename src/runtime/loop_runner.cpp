#include "selfsense/runtime/loop_runner.hpp"

#include <string>

#include "selfsense/runtime/cycle_stats.hpp"
#include "selfsense/runtime/latency_histogram.hpp"

namespace selfsense::runtime {

LoopRunner::LoopRunner(Loop& loop, Clock& clock, std::int64_t period_ns, const RtOptions& rt,
                       CycleTrigger* trigger)
    : loop_(&loop), clock_(&clock), period_ns_(period_ns), rt_(rt), trigger_(trigger) {}

LoopRunner::~LoopRunner() {
  stop();
}

RtSetupResult LoopRunner::start() {
  stop_.store(false);
  thread_ = std::thread([this] { run(); });
  std::unique_lock lock(setup_mutex_);
  setup_cv_.wait(lock, [this] { return setup_done_; });
  return setup_;
}

void LoopRunner::stop() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
}

void LoopRunner::run() {
  RtSetupResult setup = setup_realtime(rt_);
  // Held until the thread ends, dropped when it returns.
  CpuLatencyRequest latency;
  if (rt_.cpu_latency_us >= 0) {
    std::string why;
    latency = CpuLatencyRequest(rt_.cpu_latency_us, &why);
    setup.cpu_latency_held = latency.held();
    if (!latency.held()) setup.notes.push_back(why);
  }
  Pacer pacer(*clock_, period_ns_);
  CycleStats cycle_stats(period_ns_);
  LatencyHistogram trigger_wake;  // paced by the trigger: its time stamp to the wake-up
  StatusSnapshot timing;
  {
    const std::lock_guard lock(setup_mutex_);
    setup_ = std::move(setup);
    setup_done_ = true;
  }
  setup_cv_.notify_all();
  pacer.start();
  std::int64_t cycle = 0;
  std::int64_t late = 0;  // triggered cycles that started late
  while (!stop_.load(std::memory_order_relaxed)) {
    bool overrun = false;
    std::int64_t missed = 0;
    if (trigger_ != nullptr) {
      overrun = !wait_trigger();
      if (overrun) ++late;
      ++cycle;
      // Wake-up latency: from the trigger's own time stamp (the edge) to now.
      const std::int64_t fired = trigger_->fired_ns();
      if (!overrun && fired >= 0) {
        const std::int64_t woke = clock_->now_ns() - fired;
        if (woke >= 0) trigger_wake.record(woke);
      }
    } else {
      const Pacer::Tick tick = pacer.wait();
      overrun = tick.overrun;
      missed = tick.missed;
      cycle = tick.cycle;
    }
    if (stall_.load(std::memory_order_relaxed)) continue;
    const std::int64_t begin = clock_->now_ns();
    loop_->cycle(overrun, missed);
    cycle_stats.record(clock_->now_ns() - begin);
    progress_.fetch_add(1, std::memory_order_relaxed);
    if (cycle % 1000 == 0) {
      const PacerStats& p = pacer.stats();
      timing.overruns = trigger_ != nullptr ? late : p.overruns;
      timing.missed_periods = trigger_ != nullptr ? late : p.missed_periods;
      timing.last_overrun_cycle = p.last_overrun_cycle;
      const LatencyHistogram& wake = trigger_ != nullptr ? trigger_wake : p.wake_latency;
      timing.wake_latency_p50_ns = wake.percentile_ns(0.5);
      timing.wake_latency_p99_ns = wake.percentile_ns(0.99);
      timing.wake_latency_max_ns = wake.max_ns();
      timing.cycle_time_p50_ns = cycle_stats.percentile_ns(0.5);
      timing.cycle_time_p99_ns = cycle_stats.percentile_ns(0.99);
      timing.cycle_time_max_ns = cycle_stats.max_ns();
      loop_->set_timing(timing);
    }
  }
}

bool LoopRunner::wait_trigger() noexcept {
  const CycleTrigger::Result r = trigger_->wait(2 * period_ns_);
  if (r == CycleTrigger::Result::kError) {
    // The line cannot be waited on: one period of sleep keeps the loop from spinning while
    // its cycles report the fault.
    clock_->sleep_until_ns(clock_->now_ns() + period_ns_);
  }
  return r == CycleTrigger::Result::kReady;
}

}  // namespace selfsense::runtime
