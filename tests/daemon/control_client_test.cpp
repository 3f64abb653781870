// The client's failures: each names the socket and the cause, and none waits past its timeout.
#include "selfsense/daemon/control_client.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <string>

#include "daemon/server_support.hpp"

namespace selfsense::daemon {
namespace {

using std::chrono::milliseconds;

std::string failure(const std::function<void()>& run) {
  try {
    run();
  } catch (const ControlClientError& e) {
    return e.what();
  }
  return "no error";
}

TEST(ControlClient, AMissingSocketIsNamedWithTheCause) {
  const test::TempDir dir;
  EXPECT_EQ(failure([&] { ControlClient c(dir.socket(), milliseconds(500)); }),
            "cannot connect to " + dir.socket().string() + ": No such file or directory");
  EXPECT_EQ(
      failure([&] { ControlClient c("/tmp/" + std::string(200, 'y'), milliseconds(500)); }),
      "cannot connect to /tmp/" + std::string(200, 'y') + ": a socket path has 1 to 107 bytes");
}

TEST(ControlClient, AServerThatNeverAnswersTimesOut) {
  const test::TempDir dir;
  // Listens but never accepts: the connection is made, the reply never comes.
  const int listener = ::socket(AF_UNIX, SOCK_STREAM, 0);
  const sockaddr_un address = test::unix_address(dir.socket());
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-reinterpret-cast): the sockets API takes sockaddr*.
  ASSERT_EQ(::bind(listener, reinterpret_cast<const sockaddr*>(&address), sizeof address), 0);
  ASSERT_EQ(::listen(listener, 4), 0);
  ControlClient c(dir.socket(), milliseconds(200));
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(failure([&] { static_cast<void>(c.exchange(R"({"request":"status"})")); }),
            "no reply from " + dir.socket().string() + " within 0.2 s");
  const auto waited = std::chrono::steady_clock::now() - t0;
  EXPECT_GE(waited, milliseconds(200));
  EXPECT_LT(waited, milliseconds(2000));
  ::close(listener);
}

TEST(ControlClient, AClosedConnectionIsAnError) {
  const test::TempDir dir;
  const int listener = ::socket(AF_UNIX, SOCK_STREAM, 0);
  const sockaddr_un address = test::unix_address(dir.socket());
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-reinterpret-cast): the sockets API takes sockaddr*.
  ASSERT_EQ(::bind(listener, reinterpret_cast<const sockaddr*>(&address), sizeof address), 0);
  ASSERT_EQ(::listen(listener, 4), 0);
  ControlClient c(dir.socket(), milliseconds(2000));
  const int accepted = ::accept(listener, nullptr, nullptr);
  ASSERT_GE(accepted, 0);
  const std::string half = R"({"ok":tr)";
  ASSERT_EQ(::send(accepted, half.data(), half.size(), 0), static_cast<ssize_t>(half.size()));
  ::close(accepted);
  EXPECT_EQ(failure([&] { static_cast<void>(c.receive_line()); }),
            "the daemon closed the connection at " + dir.socket().string());
  ::close(listener);
}

}  // namespace
}  // namespace selfsense::daemon
