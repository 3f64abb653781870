// The control server with a fake handler: requests in order, many clients, hostile clients
// (garbage, endless lines, not reading, flooding, idling) and the bounds that contain them.
#include "selfsense/daemon/control_server.hpp"

#include <gtest/gtest.h>
#include <poll.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "daemon/server_support.hpp"
#include "selfsense/daemon/control_client.hpp"

namespace selfsense::daemon {
namespace {

using std::chrono::milliseconds;
using Clock = std::chrono::steady_clock;

constexpr milliseconds kTimeout{5000};

nlohmann::json reply_of(const std::string& line) {
  return nlohmann::json::parse(line);
}

class ControlServerTest : public ::testing::Test {
 protected:
  ControlServerConfig config() const {
    ControlServerConfig c;
    c.path = dir.socket();
    return c;
  }
  void start(const ControlServerConfig& c) {
    server = std::make_unique<ControlServer>(c, handler, log.sink());
    server->start();
  }
  void start() { start(config()); }
  ControlClient client() const { return ControlClient(dir.socket(), kTimeout); }

  test::TempDir dir;
  test::FakeHandler handler;
  test::LogLines log;
  std::unique_ptr<ControlServer> server;
};

TEST_F(ControlServerTest, AnswersARequestAndHandsThePeerToTheHandler) {
  start();
  ControlClient c = client();
  const auto reply = reply_of(c.exchange(R"({"request":"status"})"));
  EXPECT_EQ(reply.at("ok"), true);
  EXPECT_EQ(reply.at("state"), "ready");
  ASSERT_EQ(handler.requests().size(), 1U);
  EXPECT_TRUE(std::holds_alternative<StatusRequest>(handler.requests()[0]));
  const PeerCredentials peer = handler.peers().at(0);
  EXPECT_EQ(peer.pid, ::getpid());
  EXPECT_EQ(peer.uid, ::geteuid());
  EXPECT_EQ(peer.gid, ::getegid());
  EXPECT_TRUE(
      log.contains("(pid " + std::to_string(::getpid()) + ", uid " + std::to_string(::geteuid())));
  const ControlServerCounters n = server->counters();
  EXPECT_EQ(n.accepted, 1U);
  EXPECT_EQ(n.requests, 1U);
  EXPECT_EQ(n.errors, 0U);
  EXPECT_EQ(n.clients, 1U);
}

TEST_F(ControlServerTest, InvalidRequestsGetTheErrorAndNeverReachTheHandler) {
  start();
  ControlClient c = client();
  EXPECT_EQ(
      c.exchange(R"({"request":"setpoint","value":0.02})"),
      R"({"error":"setpoint.value: 0.02 is outside [-0.0001, 0.0015] for position","ok":false})");
  EXPECT_EQ(
      c.exchange(R"({"request":"mode","name":"fast"})"),
      R"x({"error":"mode.name: \"fast\" is not a mode (position, force, open-loop, damping)","ok":false})x");
  EXPECT_TRUE(handler.requests().empty());
  const ControlServerCounters n = server->counters();
  EXPECT_EQ(n.requests, 2U);
  EXPECT_EQ(n.rejected, 2U);
  EXPECT_EQ(n.errors, 2U);
}

TEST_F(ControlServerTest, GarbageAndBinaryBytesGetErrorsAndTheConnectionGoesOn) {
  start();
  ControlClient c = client();
  c.send(std::string("\x00\xff\xfe garbage \x01\x02\n", 15));
  c.send("{\"request\":\"status\"}\r\n");  // CRLF is accepted
  c.send("\n   \n");                       // blank lines are ignored
  c.send("{\"request\":\"setpoint\",\"value\":0.02}\n");
  c.send("{\"request\":\"arm\"}\n");
  EXPECT_EQ(reply_of(c.receive_line()).at("error").get<std::string>().rfind("malformed JSON: ", 0),
            0U);
  EXPECT_EQ(reply_of(c.receive_line()).at("ok"), true);
  EXPECT_EQ(reply_of(c.receive_line()).at("ok"), false);
  EXPECT_EQ(c.receive_line(), R"({"ok":true})");
  const auto got = handler.requests();
  ASSERT_EQ(got.size(), 2U);
  EXPECT_TRUE(std::holds_alternative<StatusRequest>(got[0]));
  EXPECT_TRUE(std::holds_alternative<ArmRequest>(got[1]));
  EXPECT_EQ(server->counters().requests, 4U);
  EXPECT_EQ(server->counters().rejected, 2U);
}

TEST_F(ControlServerTest, PipelinedRequestsAreAnsweredInOrder) {
  start();
  ControlClient c = client();
  std::string batch;
  for (int i = 0; i < 100; ++i) {
    batch += R"({"request":"setpoint","value":)" + std::to_string(i * 1e-5) + "}\n";
  }
  c.send(batch);
  for (int i = 0; i < 100; ++i) {
    EXPECT_DOUBLE_EQ(reply_of(c.receive_line()).at("value").get<double>(), i * 1e-5);
  }
}

TEST_F(ControlServerTest, LastLineWithoutNewlineIsAnsweredOnHalfClose) {
  start();
  const int fd = test::connect_raw(dir.socket());
  ASSERT_GE(fd, 0);
  const std::string request = R"({"request":"arm"})";
  ASSERT_EQ(::send(fd, request.data(), request.size(), MSG_NOSIGNAL),
            static_cast<ssize_t>(request.size()));
  ::shutdown(fd, SHUT_WR);
  EXPECT_EQ(test::read_until_closed(fd), "{\"ok\":true}\n");
  ::close(fd);
}

TEST_F(ControlServerTest, ManyClientsAtOnceEachGetTheirOwnReplies) {
  start();
  constexpr int kClients = 8;
  constexpr int kEach = 200;
  std::vector<std::thread> threads;
  std::atomic<int> wrong{0};
  threads.reserve(kClients);
  for (int k = 0; k < kClients; ++k) {
    threads.emplace_back([&, k] {
      ControlClient c = client();
      for (int i = 0; i < kEach; ++i) {
        const double value = (k * kEach + i) * 1e-7;
        const auto reply = reply_of(c.exchange(to_json(SetpointRequest{value}).dump()));
        if (reply.at("value").get<double>() != value) ++wrong;
      }
    });
  }
  // Counters are read while the server thread writes them.
  std::uint64_t last = 0;
  while (last < std::uint64_t{kClients} * kEach) {
    const std::uint64_t now = server->counters().requests;
    EXPECT_GE(now, last);
    last = now;
    std::this_thread::yield();
  }
  for (std::thread& t : threads)
    t.join();
  EXPECT_EQ(wrong.load(), 0);
  EXPECT_EQ(handler.requests().size(), static_cast<std::size_t>(kClients * kEach));
  EXPECT_EQ(server->counters().accepted, static_cast<std::uint64_t>(kClients));
}

TEST_F(ControlServerTest, ExtraClientsBeyondTheLimitAreTurnedAway) {
  ControlServerConfig c = config();
  c.max_clients = 4;
  start(c);
  std::vector<ControlClient> clients;
  for (int i = 0; i < 4; ++i) {
    clients.push_back(client());
    EXPECT_EQ(clients.back().exchange(R"({"request":"arm"})"), R"({"ok":true})");
  }
  ControlClient extra = client();
  EXPECT_EQ(extra.receive_line(),
            R"({"error":"too many clients (limit 4); try again later","ok":false})");
  EXPECT_THROW(static_cast<void>(extra.receive_line()), ControlClientError);
  EXPECT_EQ(server->counters().refused, 1U);
  // The served ones go on, and a slot that frees up is given to the next client.
  EXPECT_EQ(clients.front().exchange(R"({"request":"arm"})"), R"({"ok":true})");
  clients.pop_back();
  EXPECT_TRUE(test::eventually([&] { return server->counters().clients == 3; }));
  ControlClient next = client();
  EXPECT_EQ(next.exchange(R"({"request":"arm"})"), R"({"ok":true})");
}

TEST_F(ControlServerTest, AnEndlessLineGetsAnErrorAndTheClientIsClosed) {
  ControlServerConfig c = config();
  c.max_line_bytes = 1024;
  start(c);
  const int fd = test::connect_raw(dir.socket());
  ASSERT_GE(fd, 0);
  // Keep sending without a newline until the server hangs up.
  const std::string chunk(4096, 'x');
  ssize_t sent = 0;
  for (int i = 0; i < 1000 && sent >= 0; ++i)
    sent = ::send(fd, chunk.data(), chunk.size(), MSG_NOSIGNAL);
  EXPECT_LT(sent, 0);  // EPIPE: closed by the server
  EXPECT_EQ(
      test::read_until_closed(fd),
      "{\"error\":\"request line longer than 1024 bytes; closing the connection\",\"ok\":false}\n");
  ::close(fd);
  EXPECT_EQ(server->counters().oversize_lines, 1U);
  // A finished line over the limit is refused the same way.
  ControlClient other = client();
  other.send(std::string(2000, ' ') + R"({"request":"status"})" + "\n");
  EXPECT_EQ(reply_of(other.receive_line()).at("ok"), false);
  EXPECT_THROW(static_cast<void>(other.receive_line()), ControlClientError);
  EXPECT_EQ(server->counters().oversize_lines, 2U);
  EXPECT_TRUE(handler.requests().empty());
}

TEST_F(ControlServerTest, AClientThatNeverReadsIsDroppedWhileOthersAreServed) {
  ControlServerConfig c = config();
  c.max_output_bytes = std::size_t{64} * 1024;
  start(c);
  handler.status_padding = 4000;  // 4 kB per reply: 1000 unread replies are 4 MB
  const int slow = test::connect_raw(dir.socket());
  ASSERT_GE(slow, 0);
  std::atomic<bool> slow_cut{false};
  std::thread flooder([&] {
    const std::string request = "{\"request\":\"status\"}\n";
    for (int i = 0; i < 1000; ++i) {
      if (::send(slow, request.data(), request.size(), MSG_NOSIGNAL) < 0) {
        slow_cut = true;
        return;
      }
    }
  });
  ControlClient good = client();
  milliseconds worst{0};
  for (int i = 0; i < 50; ++i) {
    const auto t0 = Clock::now();
    EXPECT_EQ(reply_of(good.exchange(R"({"request":"status"})")).at("ok"), true);
    worst = std::max(worst, std::chrono::duration_cast<milliseconds>(Clock::now() - t0));
  }
  flooder.join();
  EXPECT_TRUE(test::eventually([&] { return server->counters().dropped_slow == 1; }));
  EXPECT_TRUE(log.contains("dropped"));
  EXPECT_LT(worst, milliseconds(1000));
  std::printf("slow client cut while sending: %s; worst reply to the good client: %lld ms\n",
              slow_cut ? "yes" : "no (all requests were in the socket first)",
              static_cast<long long>(worst.count()));
  ::close(slow);
}

TEST_F(ControlServerTest, AFloodFromOneClientTakesTurnsWithTheOthers) {
  start();
  constexpr int kFlood = 20000;
  ControlClient flood = client();
  std::thread writer([&] {
    std::string batch;
    for (int i = 0; i < kFlood; ++i)
      batch += "{\"request\":\"arm\"}\n";
    flood.send(batch);
  });
  int flood_ok = 0;
  std::thread reader([&] {
    for (int i = 0; i < kFlood; ++i)
      flood_ok += flood.receive_line() == R"({"ok":true})" ? 1 : 0;
  });
  ControlClient other = client();
  milliseconds worst{0};
  for (int i = 0; i < 100; ++i) {
    const auto t0 = Clock::now();
    EXPECT_EQ(reply_of(other.exchange(R"({"request":"status"})")).at("ok"), true);
    worst = std::max(worst, std::chrono::duration_cast<milliseconds>(Clock::now() - t0));
  }
  writer.join();
  reader.join();
  EXPECT_EQ(flood_ok, kFlood);
  EXPECT_LT(worst, milliseconds(1000));
  EXPECT_EQ(server->counters().requests, static_cast<std::uint64_t>(kFlood + 100));
  EXPECT_EQ(server->counters().dropped_slow, 0U);
  std::printf("worst reply to another client during a %d-request flood: %lld ms\n", kFlood,
              static_cast<long long>(worst.count()));
}

TEST_F(ControlServerTest, IdleClientsAreClosedActiveOnesAreNot) {
  ControlServerConfig c = config();
  c.idle_timeout = milliseconds(400);
  start(c);
  ControlClient idle = client();
  ControlClient busy = client();
  for (int i = 0; i < 20; ++i) {
    EXPECT_EQ(busy.exchange(R"({"request":"arm"})"), R"({"ok":true})");
    std::this_thread::sleep_for(milliseconds(50));
  }
  EXPECT_EQ(idle.receive_line(),
            R"({"error":"idle for 400 ms; closing the connection","ok":false})");
  EXPECT_THROW(static_cast<void>(idle.receive_line()), ControlClientError);
  EXPECT_EQ(server->counters().idle_closed, 1U);
}

TEST_F(ControlServerTest, HandlerFailuresBecomeInternalErrors) {
  start();
  ControlClient c = client();
  handler.misbehave = 1;
  EXPECT_EQ(c.exchange(R"({"request":"arm"})"), R"({"error":"internal error: boom","ok":false})");
  handler.misbehave = 2;
  EXPECT_EQ(c.exchange(R"({"request":"arm"})"),
            R"({"error":"internal error: the daemon's reply has no \"ok\"","ok":false})");
  handler.misbehave = 0;
  EXPECT_EQ(c.exchange(R"({"request":"arm"})"), R"({"ok":true})");
  EXPECT_EQ(server->counters().errors, 2U);
  EXPECT_EQ(server->counters().rejected, 0U);
}

TEST_F(ControlServerTest, StopClosesClientsAndRemovesTheSocket) {
  start();
  ControlClient c = client();
  EXPECT_EQ(c.exchange(R"({"request":"arm"})"), R"({"ok":true})");
  EXPECT_TRUE(server->running());
  server->stop();
  EXPECT_FALSE(server->running());
  EXPECT_FALSE(std::filesystem::exists(dir.socket()));
  EXPECT_THROW(static_cast<void>(c.exchange(R"({"request":"arm"})")), ControlClientError);
  server->stop();  // idempotent
  // And it can serve again.
  server->start();
  EXPECT_EQ(client().exchange(R"({"request":"arm"})"), R"({"ok":true})");
  EXPECT_EQ(server->counters().accepted, 1U);
}

}  // namespace
}  // namespace selfsense::daemon
