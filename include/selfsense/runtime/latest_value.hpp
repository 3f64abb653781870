// The newest snapshot of a value, published by one writer and read by any number of readers on
// other threads, where the writer never waits for a reader (a sequence lock). The loop publishes
// its status snapshot this way; the control socket and the telemetry read it.
//
// Real-time safe: publish() (wait-free: a fixed number of stores, no lock, no allocation).
// read() is lock-free but not wait-free: it retries while a publish overlaps it, which at a
// 20 kHz publish rate and a copy of a few hundred bytes succeeds within a retry or two.
//
// Why it is correct (H.-J. Boehm, "Can seqlocks get along with programming language memory
// models?", 2012). The sequence number is even when the value is stable and odd while the writer
// is storing. The writer makes it odd, issues a release fence, stores the words, then makes it
// even again with release order. A reader loads the sequence with acquire order, loads the
// words, issues an acquire fence and loads the sequence again: if both loads saw the same even
// number, no store of the writer overlapped the copy, so the copy is one whole snapshot. The
// value is kept as relaxed atomic words rather than a plain T so that the overlapping accesses
// a reader then throws away are not a data race (undefined behaviour, and ThreadSanitizer
// reports it).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace selfsense::runtime {

template <typename T>
class LatestValue final {
  static_assert(std::is_trivially_copyable_v<T>, "LatestValue holds trivially copyable values");
  static_assert(std::is_default_constructible_v<T>, "LatestValue needs a default value");

 public:
  LatestValue() noexcept { publish(T{}); }
  explicit LatestValue(const T& initial) noexcept { publish(initial); }

  // Writer only (one thread). Never waits.
  void publish(const T& value) noexcept {
    std::array<std::uint64_t, kWords> words{};
    std::memcpy(words.data(), &value, sizeof(T));
    const std::uint64_t seq = sequence_.load(std::memory_order_relaxed);
    sequence_.store(seq + 1, std::memory_order_relaxed);
    std::atomic_thread_fence(std::memory_order_release);
    for (std::size_t i = 0; i < kWords; ++i)
      words_[i].store(words[i], std::memory_order_relaxed);
    sequence_.store(seq + 2, std::memory_order_release);
  }

  // Any thread. One attempt: true and a whole snapshot in out, or false if a publish overlapped.
  bool try_read(T& out) const noexcept {
    const std::uint64_t before = sequence_.load(std::memory_order_acquire);
    if ((before & 1U) != 0) return false;
    std::array<std::uint64_t, kWords> words{};
    for (std::size_t i = 0; i < kWords; ++i)
      words[i] = words_[i].load(std::memory_order_relaxed);
    std::atomic_thread_fence(std::memory_order_acquire);
    if (sequence_.load(std::memory_order_relaxed) != before) return false;
    std::memcpy(static_cast<void*>(&out), words.data(), sizeof(T));  // T is trivially copyable
    return true;
  }

  // Any thread. Retries until it gets a whole snapshot.
  [[nodiscard]] T read() const noexcept {
    T out{};
    while (!try_read(out)) {
    }
    return out;
  }

  // How many times a value was published (the initial value counts as one).
  [[nodiscard]] std::uint64_t version() const noexcept {
    return sequence_.load(std::memory_order_acquire) / 2;
  }

 private:
  static constexpr std::size_t kWords = (sizeof(T) + sizeof(std::uint64_t) - 1) / 8;

  std::atomic<std::uint64_t> sequence_{0};
  std::array<std::atomic<std::uint64_t>, kWords> words_{};
};

}  // namespace selfsense::runtime
