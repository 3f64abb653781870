// Execution time of the loop's cycles: the loop measures read -> estimate -> control -> write
// on the monotonic clock and calls record(end - start) once per cycle. Count, sum, mean, max
// and percentiles come from a LatencyHistogram (log2 buckets, see latency_histogram.hpp); a
// budget, when set, counts the cycles whose work took longer than it (the early warning
// before the pacer sees a missed deadline).
// record() and every reader are real-time safe: no allocation, no exceptions, no locks.
#pragma once

#include <cstdint>

#include "selfsense/runtime/latency_histogram.hpp"

namespace selfsense::runtime {

class CycleStats final {
 public:
  // budget_ns <= 0: no budget.
  explicit CycleStats(std::int64_t budget_ns = 0) noexcept : budget_ns_(budget_ns) {}

  void record(std::int64_t exec_ns) noexcept {
    histogram_.record(exec_ns);
    last_ns_ = exec_ns;
    if (budget_ns_ > 0 && exec_ns > budget_ns_) ++over_budget_;
  }
  void reset() noexcept {
    histogram_.reset();
    last_ns_ = 0;
    over_budget_ = 0;
  }

  [[nodiscard]] std::int64_t count() const noexcept { return histogram_.count(); }
  [[nodiscard]] std::int64_t sum_ns() const noexcept { return histogram_.sum_ns(); }
  [[nodiscard]] double mean_ns() const noexcept { return histogram_.mean_ns(); }
  [[nodiscard]] std::int64_t max_ns() const noexcept { return histogram_.max_ns(); }
  [[nodiscard]] std::int64_t percentile_ns(double q) const noexcept {
    return histogram_.percentile_ns(q);
  }
  [[nodiscard]] std::int64_t last_ns() const noexcept { return last_ns_; }
  [[nodiscard]] std::int64_t budget_ns() const noexcept { return budget_ns_; }
  [[nodiscard]] std::int64_t over_budget() const noexcept { return over_budget_; }
  [[nodiscard]] const LatencyHistogram& histogram() const noexcept { return histogram_; }

 private:
  LatencyHistogram histogram_{};
  std::int64_t budget_ns_{0};
  std::int64_t last_ns_{0};
  std::int64_t over_budget_{0};
};

}  // namespace selfsense::runtime
