// A single-producer single-consumer lock-free ring: how the real-time loop hands its samples to
// the threads that record and publish them without ever waiting for them.
//
// One thread (the producer) calls try_push(); one other thread (the consumer) calls try_pop()
// and pop_into(). size(), capacity(), pushed_total() and popped_total() may be called from any
// thread. The capacity is fixed at construction (rounded up to a power of two); the slots are
// allocated there and nowhere else.
//
// Real-time safe: try_push, try_pop, pop_into, size and the totals (no allocation, no lock, no
// system call, no exception; wait-free: a bounded number of steps whatever the other side does).
//
// Why it is correct. head_ counts the items ever pushed and is written only by the producer;
// tail_ counts the items ever popped and is written only by the consumer. Both are 64-bit and
// only grow, so they never wrap in practice (2^64 items at 20 kHz take 29 million years) and
// head_ - tail_ is the fill level with no ambiguity between full and empty. Item i lives in
// slot i & mask_.
//  - The producer writes slot head_ and then stores head_ + 1 with release order; the consumer
//    loads head_ with acquire order before it reads that slot. Release/acquire makes the slot's
//    contents visible to the consumer before it can see the new head_.
//  - The consumer reads slot tail_ and then stores tail_ + 1 with release order; the producer
//    loads tail_ with acquire order before it decides a slot is free and overwrites it, so a
//    slot is never overwritten while the consumer may still read it.
//  - Each side keeps a private copy of the other side's index and reloads it only when the copy
//    says full (producer) or empty (consumer), so the common case touches no shared cache line
//    other than its own index.
// head_ and tail_ sit on separate cache lines so that the two threads do not invalidate each
// other's line on every operation (false sharing).
#pragma once

#include <algorithm>
#include <atomic>
#include <cassert>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <type_traits>

namespace selfsense::runtime {

// 64 bytes on the x86-64 and ARM cores the daemon targets. (std::hardware_destructive_
// interference_size would warn that its value may change between compiler versions.)
inline constexpr std::size_t kCacheLineBytes = 64;

template <typename T>
class SpscRing final {
  static_assert(std::is_trivially_copyable_v<T>, "SpscRing holds trivially copyable values");

 public:
  // Not real-time safe: allocates. capacity >= 1; rounded up to a power of two.
  explicit SpscRing(std::size_t capacity)
      : capacity_(round_up_pow2(capacity)),
        mask_(capacity_ - 1),
        slots_(std::make_unique<T[]>(capacity_)) {}

  SpscRing(const SpscRing&) = delete;
  SpscRing& operator=(const SpscRing&) = delete;
  SpscRing(SpscRing&&) = delete;
  SpscRing& operator=(SpscRing&&) = delete;
  ~SpscRing() = default;

  // Producer only. False (and nothing stored) when the ring is full.
  bool try_push(const T& value) noexcept {
    const std::uint64_t head = producer_.index.load(std::memory_order_relaxed);
    if (head - producer_.other_cached >= capacity_) {
      producer_.other_cached = consumer_.index.load(std::memory_order_acquire);
      if (head - producer_.other_cached >= capacity_) return false;
    }
    slots_[slot(head)] = value;
    producer_.index.store(head + 1, std::memory_order_release);
    return true;
  }

  // Consumer only. False when the ring is empty.
  bool try_pop(T& out) noexcept {
    const std::uint64_t tail = consumer_.index.load(std::memory_order_relaxed);
    if (tail == consumer_.other_cached) {
      consumer_.other_cached = producer_.index.load(std::memory_order_acquire);
      if (tail == consumer_.other_cached) return false;
    }
    out = slots_[slot(tail)];
    consumer_.index.store(tail + 1, std::memory_order_release);
    return true;
  }

  // Consumer only. Moves up to out.size() items, oldest first, into out; returns how many.
  // One acquire and one release for the whole batch.
  std::size_t pop_into(std::span<T> out) noexcept {
    const std::uint64_t tail = consumer_.index.load(std::memory_order_relaxed);
    consumer_.other_cached = producer_.index.load(std::memory_order_acquire);
    const auto available = static_cast<std::size_t>(consumer_.other_cached - tail);
    const std::size_t n = std::min(available, out.size());
    if (n == 0) return 0;
    const std::size_t first = slot(tail);
    const std::size_t before_wrap = std::min(n, capacity_ - first);
    std::copy_n(slots_.get() + first, before_wrap, out.data());
    std::copy_n(slots_.get(), n - before_wrap, out.data() + before_wrap);
    consumer_.index.store(tail + n, std::memory_order_release);
    return n;
  }

  // Any thread. Exact from either end; from a third thread a value that was true at some
  // moment during the call.
  [[nodiscard]] std::size_t size() const noexcept {
    const std::uint64_t tail = consumer_.index.load(std::memory_order_acquire);
    const std::uint64_t head = producer_.index.load(std::memory_order_acquire);
    return head >= tail ? static_cast<std::size_t>(head - tail) : 0;
  }
  [[nodiscard]] std::size_t capacity() const noexcept { return capacity_; }
  // Items ever pushed / popped (monotonic).
  [[nodiscard]] std::uint64_t pushed_total() const noexcept {
    return producer_.index.load(std::memory_order_acquire);
  }
  [[nodiscard]] std::uint64_t popped_total() const noexcept {
    return consumer_.index.load(std::memory_order_acquire);
  }

 private:
  static std::size_t round_up_pow2(std::size_t n) noexcept {
    assert(n >= 1 && n <= std::numeric_limits<std::size_t>::max() / 2 + 1);
    std::size_t p = 1;
    while (p < n)
      p <<= 1U;
    return p;
  }

  // One side's index and its private copy of the other side's, alone on a cache line.
  struct alignas(kCacheLineBytes) Side {
    std::atomic<std::uint64_t> index{0};
    std::uint64_t other_cached{0};
  };

  // The slot of a 64-bit index: below the capacity, so it fits std::size_t on 32-bit targets.
  [[nodiscard]] std::size_t slot(std::uint64_t index) const noexcept {
    return static_cast<std::size_t>(index & mask_);
  }

  const std::size_t capacity_;
  const std::size_t mask_;
  std::unique_ptr<T[]> slots_;
  Side producer_{};  // head: written by the producer
  Side consumer_{};  // tail: written by the consumer
};

}  // namespace selfsense::runtime
