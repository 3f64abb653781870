#include "soak/socket_abuse.hpp"

#include <sys/socket.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <string_view>

#include "selfsense/daemon/control_client.hpp"

namespace selfsense::soak {
namespace {

using daemon::ControlClient;
using daemon::ControlClientError;

constexpr std::chrono::milliseconds kTimeout{5000};
constexpr std::string_view kStatus = R"({"request":"status"})";
constexpr std::string_view kTooMany = "too many clients";

// The reply's "ok", or nullopt when it is not a JSON object with a boolean "ok".
std::optional<bool> ok_of(const std::string& line) {
  const nlohmann::json reply = nlohmann::json::parse(line, nullptr, false);
  if (!reply.is_object() || !reply.contains("ok") || !reply["ok"].is_boolean()) return std::nullopt;
  return reply["ok"].get<bool>();
}

// A line of random bytes without '\n' that is never a valid request: printable noise, broken
// JSON, JSON of the wrong shape, bytes that are not UTF-8.
std::string garbage_line(std::mt19937& random) {
  static constexpr std::array<std::string_view, 8> kShapes{
      R"({"request":)",      R"({"request":"arm","x":1})",
      R"([1,2,3])",          R"({"request":"setpoint","value":1e999})",
      R"("status")",         R"({"request":"wave","shape":"sine"})",
      "\xff\xfe\x80 binary", R"({"request":"mode","name":"fast"})"};
  std::string line(kShapes.at(random() % kShapes.size()));
  std::uniform_int_distribution<int> byte(1, 255);
  const std::size_t noise = random() % 64;
  for (std::size_t i = 0; i < noise; ++i) {
    auto c = static_cast<char>(byte(random));
    if (c == '\n' || c == '\r') c = '#';
    line += c;
  }
  return line;
}

// True when this first reply says the server had no slot for us.
bool refused(const std::string& line) {
  return line.find(kTooMany) != std::string::npos;
}

// Sends what the socket takes. A server that refused us (too many clients) or dropped us may
// have closed before all was sent; what it said before closing is still there to read.
void send_lenient(ControlClient& c, std::string_view bytes) {
  try {
    c.send(bytes);
  } catch (const ControlClientError&) {
  }
}

}  // namespace

SocketAbuse::SocketAbuse(std::filesystem::path socket, std::size_t max_clients, int threads,
                         std::uint32_t seed)
    : socket_(std::move(socket)), max_clients_(max_clients) {
  for (int i = 0; i < threads; ++i) {
    threads_.emplace_back([this, seed, i] { run(seed + static_cast<std::uint32_t>(i)); });
  }
}

SocketAbuse::~SocketAbuse() {
  stop();
}

void SocketAbuse::stop() {
  stop_.store(true);
  for (std::thread& t : threads_) {
    if (t.joinable()) t.join();
  }
}

AbuseCounts SocketAbuse::counts() const {
  const std::lock_guard lock(mutex_);
  return counts_;
}

void SocketAbuse::run(std::uint32_t seed) {
  std::mt19937 random(seed);
  const auto fail = [this](const std::string& what) {
    const std::lock_guard lock(mutex_);
    if (counts_.failures.size() < 50) counts_.failures.push_back(what);
  };
  const auto count = [this](std::uint64_t AbuseCounts::*field, std::uint64_t n = 1) {
    const std::lock_guard lock(mutex_);
    counts_.*field += n;
  };
  const auto busy = [&] { count(&AbuseCounts::refused_busy); };

  while (!stop_.load()) {
    try {
      switch (random() % 7) {
        case 0: {  // garbage: every line gets an error reply, the connection stays usable
          ControlClient c(socket_, kTimeout);
          const std::size_t n = 1 + random() % 20;
          std::string batch;
          for (std::size_t i = 0; i < n; ++i)
            batch += garbage_line(random) + "\n";
          send_lenient(c, batch);
          std::size_t answered = 0;
          for (std::size_t i = 0; i < n; ++i) {
            const std::string reply = c.receive_line();
            if (i == 0 && refused(reply)) break;
            if (ok_of(reply) != false) fail("garbage line answered with: " + reply.substr(0, 200));
            ++answered;
          }
          if (answered == 0) {
            busy();
          } else {
            const std::optional<bool> after = ok_of(c.exchange(kStatus));
            // (A refusal cannot come now: the connection was accepted and answered.)
            if (after != true) fail("no status after garbage on the same connection");
            count(&AbuseCounts::garbage_lines, answered);
          }
          break;
        }
        case 1: {  // disconnect in the middle of a line
          ControlClient c(socket_, kTimeout);
          const std::string line(kStatus);
          send_lenient(c, std::string_view(line).substr(0, 1 + random() % (line.size() - 1)));
          count(&AbuseCounts::cut_lines);
          break;
        }
        case 2: {  // a line over the server's 64 KiB limit: an error, then closed
          ControlClient c(socket_, kTimeout);
          // The server may close while the rest is still being sent; its reply came first.
          send_lenient(c, std::string(std::size_t{70} * 1024, 'x'));
          const std::string reply = c.receive_line();
          if (refused(reply)) {
            busy();
            break;
          }
          if (ok_of(reply) != false || reply.find("longer than") == std::string::npos) {
            fail("oversize line answered with: " + reply.substr(0, 200));
          }
          bool closed = false;
          try {
            static_cast<void>(c.receive_line());
          } catch (const ControlClientError&) {
            closed = true;
          }
          if (!closed) fail("the connection stayed open after an oversize line");
          count(&AbuseCounts::oversize_lines);
          break;
        }
        case 3: {  // a pipelined flood, read back: one ok reply per request, in order
          ControlClient c(socket_, kTimeout);
          // Sized to the status reply: the server keeps at most 256 KiB of unread replies per
          // client (control_server.hpp, max_output_bytes) and drops a client past that, so the
          // whole flood stays within half of it (a status with fault details is a few KiB).
          // A refused client may be closed before its request is sent: what the server said
          // first is still there to read (send_lenient).
          send_lenient(c, std::string(kStatus) + "\n");
          const std::string first = c.receive_line();
          if (refused(first)) {
            busy();
            break;
          }
          const std::size_t most = std::clamp<std::size_t>(
              (std::size_t{128} * 1024) / std::max<std::size_t>(first.size(), 1), 10, 200);
          const std::size_t n = most / 2 + random() % (most / 2);
          std::string batch;
          for (std::size_t i = 0; i < n; ++i)
            batch += std::string(kStatus) + "\n";
          send_lenient(c, batch);
          std::size_t got = 0;
          for (std::size_t i = 0; i < n; ++i) {
            const std::string reply = c.receive_line();
            if (i == 0 && refused(reply)) break;
            if (ok_of(reply) != true) fail("flood reply " + std::to_string(i) + ": " + reply);
            ++got;
          }
          if (got == 0) busy();
          count(&AbuseCounts::flood_replies, got);
          break;
        }
        case 4: {  // a flood never read: the server must drop us, not grow or stall
          ControlClient c(socket_, kTimeout);
          std::string batch;
          for (int i = 0; i < 2000; ++i)
            batch += std::string(kStatus) + "\n";
          send_lenient(c, batch);  // dropped while sending: what a non-reader earns
          std::this_thread::sleep_for(std::chrono::milliseconds(200));
          count(&AbuseCounts::unread_floods);
          break;
        }
        case 5: {  // churn: connect and leave at once
          for (int i = 0; i < 20; ++i) {
            ControlClient c(socket_, kTimeout);
            if (i % 2 == 0) ::shutdown(c.fd(), SHUT_WR);
          }
          count(&AbuseCounts::churn_connections, 20);
          break;
        }
        case 6: {  // every free slot taken: the next connection is refused; freed, served again
          const std::lock_guard slots(slots_mutex_);
          std::vector<std::unique_ptr<ControlClient>> held;
          bool saw_refusal = false;
          for (std::size_t i = 0; i <= max_clients_ + 1 && !saw_refusal; ++i) {
            auto c = std::make_unique<ControlClient>(socket_, kTimeout);
            send_lenient(*c, std::string(kStatus) + "\n");
            const std::string reply = c->receive_line();
            if (refused(reply)) {
              saw_refusal = true;
              bool closed = false;
              try {
                static_cast<void>(c->receive_line());
              } catch (const ControlClientError&) {
                closed = true;
              }
              if (!closed) fail("a refused client was not closed");
            } else if (ok_of(reply) != true) {
              fail("status while filling the slots: " + reply.substr(0, 200));
            }
            held.push_back(std::move(c));
          }
          if (!saw_refusal) {
            fail("no refusal with " + std::to_string(max_clients_ + 2) + " connections");
          }
          held.clear();
          bool served = false;
          for (int attempt = 0; attempt < 50 && !served; ++attempt) {
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
            ControlClient c(socket_, kTimeout);
            send_lenient(c, std::string(kStatus) + "\n");
            served = ok_of(c.receive_line()) == true;
          }
          if (!served) fail("no client served after the slots were freed");
          count(&AbuseCounts::max_client_rounds);
          break;
        }
        default:
          break;
      }
    } catch (const ControlClientError& e) {
      // Refused connections are closed by the server, which a send may see first.
      fail(std::string("client error: ") + e.what());
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50 + random() % 150));
  }
}

}  // namespace selfsense::soak
