#include "selfsense/runtime/latest_value.hpp"

#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <thread>

namespace selfsense::runtime {
namespace {

// 40 words, all derived from one counter: a snapshot mixing two publishes would not agree.
struct Snapshot {
  std::array<std::uint64_t, 40> words{};
  [[nodiscard]] bool consistent() const noexcept {
    for (std::size_t i = 0; i < words.size(); ++i) {
      if (words[i] != words[0] + i) return false;
    }
    return true;
  }
};

Snapshot make(std::uint64_t n) {
  Snapshot s;
  for (std::size_t i = 0; i < s.words.size(); ++i)
    s.words[i] = n * 3 + i;
  return s;
}

TEST(LatestValue, ReadsTheLastPublishedValue) {
  LatestValue<Snapshot> value(make(7));
  EXPECT_EQ(value.read().words[0], 21U);
  value.publish(make(8));
  Snapshot out;
  ASSERT_TRUE(value.try_read(out));
  EXPECT_EQ(out.words[0], 24U);
  EXPECT_TRUE(out.consistent());
  EXPECT_EQ(value.version(), 2U);
}

TEST(LatestValue, ReadersOnOtherThreadsNeverSeeATornSnapshotAndTimeMovesForward) {
  LatestValue<Snapshot> value(make(0));
  std::atomic<bool> done{false};
  constexpr std::uint64_t kPublishes = 200'000;
  std::thread writer([&] {
    for (std::uint64_t n = 1; n <= kPublishes; ++n)
      value.publish(make(n));
    done.store(true);
  });
  std::array<std::thread, 2> readers;
  std::array<std::uint64_t, 2> reads{};
  std::array<bool, 2> ok{true, true};
  for (std::size_t r = 0; r < readers.size(); ++r) {
    readers[r] = std::thread([&, r] {
      std::uint64_t last = 0;
      while (!done.load()) {
        const Snapshot s = value.read();
        if (!s.consistent() || s.words[0] / 3 < last) ok[r] = false;
        last = s.words[0] / 3;
        ++reads[r];
      }
    });
  }
  writer.join();
  for (std::thread& t : readers)
    t.join();
  EXPECT_TRUE(ok[0]);
  EXPECT_TRUE(ok[1]);
  EXPECT_EQ(value.read().words[0], kPublishes * 3);
}

}  // namespace
}  // namespace selfsense::runtime
