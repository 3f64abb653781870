// A blocking client of the control socket with a deadline per call: what `selfsense ctl` and
// the tests use to talk to the daemon (docs/control-socket.md).
#pragma once

#include <chrono>
#include <cstddef>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

namespace selfsense::daemon {

// The connection failed, timed out or broke; the message names the socket and the cause
// ("cannot connect to /run/selfsensed/control.sock: No such file or directory").
class ControlClientError final : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class ControlClient final {
 public:
  // Replies longer than this are refused as a broken server, not buffered.
  static constexpr std::size_t kMaxReplyBytes = std::size_t{16} * 1024 * 1024;

  // Connects within the timeout. Throws ControlClientError.
  ControlClient(std::filesystem::path path, std::chrono::milliseconds timeout);
  ControlClient(const ControlClient&) = delete;
  ControlClient& operator=(const ControlClient&) = delete;
  ControlClient(ControlClient&& other) noexcept;
  ControlClient& operator=(ControlClient&& other) noexcept;
  ~ControlClient();

  // Sends one request line (the newline is added) and returns the reply line without its
  // newline. Throws ControlClientError on timeout or a closed connection.
  [[nodiscard]] std::string exchange(std::string_view request);
  // Sends bytes as they are.
  void send(std::string_view bytes);
  // The next line from the server without its newline.
  [[nodiscard]] std::string receive_line();

  [[nodiscard]] int fd() const noexcept { return fd_; }

 private:
  void wait_for(short events, std::chrono::steady_clock::time_point deadline, const char* what);

  std::filesystem::path path_{};
  std::chrono::milliseconds timeout_{};
  int fd_{-1};
  std::string buffer_{};  // received bytes after the last returned line
};

}  // namespace selfsense::daemon
