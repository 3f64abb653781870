// What the control-server tests share: a temporary directory, a handler that records what it
// got, a log collector, raw socket helpers and a wait-until.
#pragma once

#include <fcntl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <mutex>
#include <stdexcept>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "daemon/test_limits.hpp"
#include "selfsense/daemon/control_server.hpp"

namespace selfsense::daemon::test {

// A fresh directory under /tmp, searchable by everyone (mode 0755) so that only the socket
// file's own mode decides who may connect; removed with everything in it.
class TempDir final {
 public:
  TempDir() {
    std::string pattern = "/tmp/selfsense-ctl-XXXXXX";
    if (::mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
    path_ = pattern;
    std::filesystem::permissions(path_, std::filesystem::perms(0755));
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  TempDir(TempDir&&) = delete;
  TempDir& operator=(TempDir&&) = delete;
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }
  [[nodiscard]] std::filesystem::path socket() const { return path_ / "control.sock"; }

 private:
  std::filesystem::path path_;
};

// Records every request it is handed. Replies: status with `status_padding` bytes of filler
// (to make replies big), setpoint echoing the value, everything else a bare ok. `misbehave`
// makes the next replies throw (1) or lack "ok" (2).
class FakeHandler final : public RequestHandler {
 public:
  RequestLimits limits() override { return limits_; }

  nlohmann::json handle(const Request& request, const PeerCredentials& peer) override {
    {
      const std::lock_guard lock(mutex_);
      requests_.push_back(request);
      peers_.push_back(peer);
    }
    if (misbehave.load() == 1) throw std::runtime_error("boom");
    if (misbehave.load() == 2) return nlohmann::json{{"state", "ready"}};
    if (std::holds_alternative<StatusRequest>(request)) {
      return ok_reply({{"state", "ready"}, {"padding", std::string(status_padding.load(), 'x')}});
    }
    if (const auto* setpoint = std::get_if<SetpointRequest>(&request)) {
      return ok_reply({{"value", setpoint->value}});
    }
    return ok_reply();
  }

  [[nodiscard]] std::vector<Request> requests() const {
    const std::lock_guard lock(mutex_);
    return requests_;
  }
  [[nodiscard]] std::vector<PeerCredentials> peers() const {
    const std::lock_guard lock(mutex_);
    return peers_;
  }

  std::atomic<std::size_t> status_padding{0};
  std::atomic<int> misbehave{0};

 private:
  RequestLimits limits_{test::limits()};
  mutable std::mutex mutex_;
  std::vector<Request> requests_;
  std::vector<PeerCredentials> peers_;
};

// Collects the server's log lines.
class LogLines final {
 public:
  ControlServerLog sink() {
    return [this](std::string_view line) {
      const std::lock_guard lock(mutex_);
      lines_.emplace_back(line);
    };
  }
  [[nodiscard]] bool contains(std::string_view text) const {
    const std::lock_guard lock(mutex_);
    for (const std::string& line : lines_) {
      if (line.find(text) != std::string::npos) return true;
    }
    return false;
  }

 private:
  mutable std::mutex mutex_;
  std::vector<std::string> lines_;
};

// Polls `done` every 2 ms until it holds or `limit` passes.
inline bool eventually(const std::function<bool()>& done,
                       std::chrono::milliseconds limit = std::chrono::seconds(5)) {
  const auto end = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < end) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return done();
}

inline sockaddr_un unix_address(const std::filesystem::path& path) {
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  std::strncpy(&address.sun_path[0], path.c_str(), sizeof address.sun_path - 1);
  return address;
}

// connect() on a new blocking socket; the fd, or -errno.
inline int connect_raw(const std::filesystem::path& path) {
  const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return -errno;
  const sockaddr_un address = unix_address(path);
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-reinterpret-cast): the sockets API takes sockaddr*.
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
    const int error = errno;
    ::close(fd);
    return -error;
  }
  return fd;
}

// Everything the peer sends until it closes (or `limit` passes).
inline std::string read_until_closed(int fd,
                                     std::chrono::milliseconds limit = std::chrono::seconds(5)) {
  timeval timeout{static_cast<time_t>(limit.count() / 1000),
                  static_cast<suseconds_t>((limit.count() % 1000) * 1000)};
  static_cast<void>(::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout));
  std::string out;
  std::array<char, 4096> chunk{};
  for (;;) {
    const ssize_t got = ::recv(fd, chunk.data(), chunk.size(), 0);
    if (got <= 0) return out;
    out.append(chunk.data(), static_cast<std::size_t>(got));
  }
}

}  // namespace selfsense::daemon::test
