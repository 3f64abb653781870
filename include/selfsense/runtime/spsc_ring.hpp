// Lock-free hand-over between exactly one producer thread and one consumer thread.
//
// SpscRing<T>: a bounded FIFO of trivially copyable values. The producer owns `head_`, the
// consumer `tail_`; each publishes its index with a release store after touching the slot and
// reads the other's with an acquire load, so a slot is never read before it is written nor
// overwritten before it is read. Capacity is a power of two fixed at construction (the only
// allocation); the indices run freely and are masked, so full and empty are told apart without
// a spare slot.
//
// LatestValue<T>: one writer publishes snapshots, readers on other threads copy the newest one.
// A sequence lock: the writer makes the sequence odd, copies, makes it even; a reader retries
// while the sequence was odd or changed during its copy. The writer never waits.
//
// try_push, try_pop, pop_into, publish: real-time safe (noexcept, no allocation, no lock).
#pragma once

#include <atomic>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <type_traits>
#include <vector>

namespace selfsense::runtime {

template <typename T>
class SpscRing {  // NOLINT(clang-analyzer-optin.performance.Padding): indices on own lines
  static_assert(std::is_trivially_copyable_v<T>);

 public:
  explicit SpscRing(std::size_t capacity)
      : slots_(std::bit_ceil(capacity < 2 ? std::size_t{2} : capacity)), mask_(slots_.size() - 1) {}

  [[nodiscard]] std::size_t capacity() const noexcept { return slots_.size(); }

  bool try_push(const T& value) noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_.load(std::memory_order_acquire) == slots_.size()) return false;
    slots_[head & mask_] = value;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  bool try_pop(T& out) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (head_.load(std::memory_order_acquire) == tail) return false;
    out = slots_[tail & mask_];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  std::size_t pop_into(std::span<T> out) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    const std::size_t available = head_.load(std::memory_order_acquire) - tail;
    const std::size_t n = available < out.size() ? available : out.size();
    for (std::size_t i = 0; i < n; ++i)
      out[i] = slots_[(tail + i) & mask_];
    tail_.store(tail + n, std::memory_order_release);
    return n;
  }

  [[nodiscard]] std::size_t size() const noexcept {
    return head_.load(std::memory_order_acquire) - tail_.load(std::memory_order_acquire);
  }

 private:
  std::vector<T> slots_;
  std::size_t mask_;
  alignas(64) std::atomic<std::size_t> head_{0};
  alignas(64) std::atomic<std::size_t> tail_{0};
};

template <typename T>
class LatestValue {
  static_assert(std::is_trivially_copyable_v<T>);

 public:
  void publish(const T& value) noexcept {
    const std::uint64_t s = sequence_.load(std::memory_order_relaxed);
    sequence_.store(s + 1, std::memory_order_relaxed);
    std::atomic_thread_fence(std::memory_order_release);
    copy_in(value);
    sequence_.store(s + 2, std::memory_order_release);
  }

  // The newest published value (T{} before the first publish).
  [[nodiscard]] T read() const noexcept {
    T out{};
    for (;;) {
      const std::uint64_t before = sequence_.load(std::memory_order_acquire);
      if ((before & 1U) == 0U) {
        copy_out(out);
        std::atomic_thread_fence(std::memory_order_acquire);
        if (sequence_.load(std::memory_order_relaxed) == before) return out;
      }
    }
  }

 private:
  // Word-wise relaxed atomics: a torn read is possible and detected, never a data race.
  static constexpr std::size_t kWords = (sizeof(T) + 7) / 8;
  void copy_in(const T& value) noexcept {
    std::uint64_t words[kWords]{};
    std::memcpy(words, &value, sizeof(T));
    for (std::size_t i = 0; i < kWords; ++i)
      data_[i].store(words[i], std::memory_order_relaxed);
  }
  void copy_out(T& out) const noexcept {
    std::uint64_t words[kWords]{};
    for (std::size_t i = 0; i < kWords; ++i)
      words[i] = data_[i].load(std::memory_order_relaxed);
    std::memcpy(&out, words, sizeof(T));
  }

  std::atomic<std::uint64_t> sequence_{0};
  std::atomic<std::uint64_t> data_[kWords]{};
};

}  // namespace selfsense::runtime
