// One client of the control server: its socket, the bytes received but not yet a full line
// and the reply bytes not yet sent. Non-blocking; used by the server thread only. Private to
// the daemon library.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "selfsense/daemon/control_server.hpp"
#include "unix_socket.hpp"

namespace selfsense::daemon::detail {

class Connection final {
 public:
  using Clock = std::chrono::steady_clock;
  enum class Read : std::uint8_t { kData, kEnd, kNothing, kBroken };
  // A line, or why there is none.
  struct Line {
    enum class Kind : std::uint8_t { kLine, kNone, kTooLong };
    Kind kind{Kind::kNone};
    std::string text{};
  };

  Connection(Fd fd, PeerCredentials peer, std::uint64_t id, Clock::time_point now);

  [[nodiscard]] int fd() const noexcept { return fd_.get(); }
  [[nodiscard]] const PeerCredentials& peer() const noexcept { return peer_; }
  [[nodiscard]] std::uint64_t id() const noexcept { return id_; }
  [[nodiscard]] Clock::time_point last_active() const noexcept { return last_active_; }

  // Receives one chunk (at most `chunk` bytes): one turn of this client in a poll round.
  Read receive(std::size_t chunk, Clock::time_point now);
  // The next complete line without "\n" (and without a trailing "\r"); after the peer's end
  // also the last unterminated one. kTooLong when a line exceeds max_bytes, finished or not.
  [[nodiscard]] Line next_line(std::size_t max_bytes, bool at_end);
  // Drops received bytes that are no longer wanted (after a too-long line).
  void discard_input() noexcept;

  void queue(std::string_view bytes);
  // Sends what the socket takes now. False when the connection is broken.
  bool send(Clock::time_point now);
  [[nodiscard]] std::size_t unsent() const noexcept { return out_.size() - sent_; }

  // No more requests are read; the client is closed once its replies are sent.
  bool closing{false};
  // Close now, unsent replies or not.
  bool dead{false};

 private:
  Fd fd_;
  PeerCredentials peer_{};
  std::uint64_t id_{0};
  Clock::time_point last_active_{};
  std::string in_{};
  std::size_t consumed_{0};  // bytes of in_ already returned as lines
  std::string out_{};
  std::size_t sent_{0};  // bytes of out_ already sent
};

}  // namespace selfsense::daemon::detail
