#include "selfsense/runtime/rt_setup.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <string>
#include <utility>

namespace selfsense::runtime {
namespace {

constexpr const char* kPath = "/dev/cpu_dma_latency";

// The value the kernel applies now (the smallest request held), or -1 when it cannot be read.
std::int64_t effective_latency_us() {
  const int fd = ::open(kPath, O_RDONLY | O_CLOEXEC);
  if (fd < 0) return -1;
  std::int32_t value = -1;
  const bool read = ::read(fd, &value, sizeof(value)) == static_cast<ssize_t>(sizeof(value));
  ::close(fd);
  return read ? value : -1;
}

// Held while the object lives (the kernel applies it: read back where the file can be read),
// dropped when it goes; without the rights, a note that names the file and the cause.
TEST(CpuLatencyRequest, IsHeldWhileItLivesOrSaysWhyNot) {
  std::string why;
  if (::access(kPath, W_OK) != 0) {
    const CpuLatencyRequest request(0, &why);
    EXPECT_FALSE(request.held());
    EXPECT_NE(why.find(kPath), std::string::npos) << why;
    GTEST_SKIP() << "no write access to " << kPath << ": the held case needs root";
  }
  const std::int64_t before = effective_latency_us();
  {
    CpuLatencyRequest request(0, &why);
    ASSERT_TRUE(request.held()) << why;
    if (before >= 0) {
      EXPECT_EQ(effective_latency_us(), 0);
    }
    CpuLatencyRequest moved = std::move(request);
    EXPECT_TRUE(moved.held());
    EXPECT_FALSE(request.held());  // NOLINT(bugprone-use-after-move): the moved-from state
    if (before >= 0) {
      EXPECT_EQ(effective_latency_us(), 0);
    }
  }
  if (before > 0) {
    EXPECT_EQ(effective_latency_us(), before);
  }
}

TEST(CpuLatencyRequest, ADefaultRequestHoldsNothing) {
  const CpuLatencyRequest request;
  EXPECT_FALSE(request.held());
}

}  // namespace
}  // namespace selfsense::runtime
