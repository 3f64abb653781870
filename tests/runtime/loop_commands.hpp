// Commands to a runtime::Loop in the tests' simulated time: the loop answers a command in the
// cycle that takes it, so a test submits and cycles until the answer comes.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>

#include "selfsense/runtime/loop.hpp"

namespace selfsense::test {

// Submits `c` under the next id and runs cycles (at most 10) until the loop answered.
inline runtime::CommandResult send_and_cycle(runtime::Loop& loop, std::uint64_t& next_id,
                                             runtime::LoopCommand c) {
  c.id = ++next_id;
  EXPECT_TRUE(loop.submit(c));
  for (int i = 0; i < 10; ++i) {
    loop.cycle(false);
    runtime::LoopAnswer a;
    if (loop.take_answer(a)) {
      EXPECT_EQ(a.id, c.id);
      return a.result;
    }
  }
  ADD_FAILURE() << "no answer";
  return runtime::CommandResult::kInvalid;
}

}  // namespace selfsense::test
