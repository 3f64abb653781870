#include "selfsense/runtime/spsc_ring.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <thread>
#include <vector>

namespace selfsense::runtime {
namespace {

TEST(SpscRing, CapacityIsRoundedUpToAPowerOfTwo) {
  EXPECT_EQ(SpscRing<int>(1).capacity(), 1U);
  EXPECT_EQ(SpscRing<int>(5).capacity(), 8U);
  EXPECT_EQ(SpscRing<int>(1024).capacity(), 1024U);
  EXPECT_EQ(SpscRing<int>(1025).capacity(), 2048U);
}

TEST(SpscRing, FullRingRefusesAndEmptyRingYieldsNothing) {
  SpscRing<int> ring(4);
  int out = 0;
  EXPECT_FALSE(ring.try_pop(out));
  for (int i = 0; i < 4; ++i)
    EXPECT_TRUE(ring.try_push(i));
  EXPECT_FALSE(ring.try_push(99));
  EXPECT_EQ(ring.size(), 4U);
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(ring.try_pop(out));
    EXPECT_EQ(out, i);
  }
  EXPECT_FALSE(ring.try_pop(out));
  EXPECT_EQ(ring.pushed_total(), 4U);
  EXPECT_EQ(ring.popped_total(), 4U);
}

TEST(SpscRing, BatchPopKeepsOrderAcrossTheWrap) {
  SpscRing<int> ring(8);
  std::array<int, 8> out{};
  int next_in = 0;
  int next_out = 0;
  // Fill levels and batch sizes chosen so that batches straddle the end of the storage.
  for (int round = 0; round < 50; ++round) {
    const int pushes = 1 + (round * 5) % 8;
    for (int i = 0; i < pushes; ++i) {
      if (ring.try_push(next_in)) ++next_in;
    }
    const std::size_t want = 1 + static_cast<std::size_t>(round * 3) % 8;
    const std::size_t got = ring.pop_into(std::span<int>(out.data(), want));
    EXPECT_LE(got, want);
    for (std::size_t i = 0; i < got; ++i)
      ASSERT_EQ(out[i], next_out++);
  }
  while (const std::size_t got = ring.pop_into(out)) {
    for (std::size_t i = 0; i < got; ++i)
      ASSERT_EQ(out[i], next_out++);
  }
  EXPECT_EQ(next_out, next_in);
  EXPECT_EQ(ring.size(), 0U);
}

struct Item {
  std::uint64_t index{0};
  std::uint64_t check{0};  // a second word, so a torn copy would show
};

// Two threads, a small ring so that both full and empty happen constantly: every item arrives,
// once, in order, whole. Also run under ThreadSanitizer (docs/recorder.md).
TEST(SpscRing, TwoThreadsMoveAMillionItemsInOrderWithoutLoss) {
  constexpr std::uint64_t kItems = 1'000'000;
  SpscRing<Item> ring(256);
  std::thread producer([&ring] {
    for (std::uint64_t i = 0; i < kItems; ++i) {
      const Item item{i, ~i};
      while (!ring.try_push(item))
        std::this_thread::yield();
    }
  });
  std::uint64_t expected = 0;
  std::vector<Item> batch(64);
  bool single = false;
  while (expected < kItems) {
    // Alternate the two ways of popping.
    single = !single;
    if (single) {
      Item item{};
      if (!ring.try_pop(item)) {
        std::this_thread::yield();
        continue;
      }
      ASSERT_EQ(item.index, expected);
      ASSERT_EQ(item.check, ~expected);
      ++expected;
      continue;
    }
    const std::size_t got = ring.pop_into(batch);
    for (std::size_t i = 0; i < got; ++i) {
      ASSERT_EQ(batch[i].index, expected);
      ASSERT_EQ(batch[i].check, ~expected);
      ++expected;
    }
  }
  producer.join();
  EXPECT_EQ(ring.size(), 0U);
  EXPECT_EQ(ring.pushed_total(), kItems);
  EXPECT_EQ(ring.popped_total(), kItems);
}

}  // namespace
}  // namespace selfsense::runtime
