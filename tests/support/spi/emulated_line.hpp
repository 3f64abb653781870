// An emulated GPIO line (include/selfsense/drivers/spi/gpio_line.hpp) for tests: an input whose
// level the test sets (each change queues an edge), or an output whose level the driver sets.
// wait_edge() does not wait: it takes a queued edge or times out at once (time is the test's to
// advance).
#pragma once

#include <cstdint>
#include <deque>

#include "selfsense/drivers/spi/gpio_line.hpp"

namespace selfsense::test {

class EmulatedLine final : public drivers::spi::GpioLine {
 public:
  explicit EmulatedLine(bool level = false) : level_(level) {}
  int read() noexcept override { return broken_ ? -1 : (level_ ? 1 : 0); }
  bool write(bool high) noexcept override {
    if (broken_) return false;
    level_ = high;
    ++writes_;
    return true;
  }
  drivers::spi::EdgeWait wait_edge(std::int64_t /*timeout_ns*/,
                                   drivers::spi::Edge* edge) noexcept override {
    if (broken_) return drivers::spi::EdgeWait::kError;
    if (edges_.empty()) return drivers::spi::EdgeWait::kTimeout;
    if (edge != nullptr) *edge = edges_.front();
    edges_.pop_front();
    return drivers::spi::EdgeWait::kEdge;
  }
  // Test side: the level changes at time t_ns (an edge is queued when it changes).
  void set_level(bool high, std::int64_t t_ns) {
    if (high != level_) edges_.push_back({high, t_ns});
    level_ = high;
  }
  void set_broken(bool broken) noexcept { broken_ = broken; }
  [[nodiscard]] bool level() const noexcept { return level_; }
  [[nodiscard]] int writes() const noexcept { return writes_; }

 private:
  bool level_;
  bool broken_{false};
  int writes_{0};
  std::deque<drivers::spi::Edge> edges_{};
};

}  // namespace selfsense::test
