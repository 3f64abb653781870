#include "selfsense/daemon/control_client.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <climits>
#include <utility>

#include "unix_socket.hpp"

namespace selfsense::daemon {
namespace {

using Clock = std::chrono::steady_clock;

std::string seconds(std::chrono::milliseconds timeout) {
  const double s = static_cast<double>(timeout.count()) / 1000.0;
  std::string text = std::to_string(s);
  text.erase(text.find_last_not_of('0') + 1);
  if (text.back() == '.') text.pop_back();
  return text + " s";
}

}  // namespace

ControlClient::ControlClient(std::filesystem::path path, std::chrono::milliseconds timeout)
    : path_(std::move(path)), timeout_(timeout) {
  const std::string where = "cannot connect to " + path_.string();
  sockaddr_un address{};
  try {
    address = detail::address_of(path_);
  } catch (const std::runtime_error& e) {
    throw ControlClientError(where + ": " + e.what());
  }
  detail::Fd fd(::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0));
  if (!fd.valid()) throw ControlClientError(where + ": " + detail::errno_text(errno));
  // A blocking connect waits while the server's backlog is full; the send timeout bounds it.
  const auto whole = std::chrono::duration_cast<std::chrono::seconds>(timeout);
  // timeval's fields are 32 bits on armhf: a timeout in seconds and its microseconds fit.
  const timeval limit{
      static_cast<decltype(timeval::tv_sec)>(whole.count()),
      static_cast<decltype(timeval::tv_usec)>(
          std::chrono::duration_cast<std::chrono::microseconds>(timeout - whole).count())};
  static_cast<void>(::setsockopt(fd.get(), SOL_SOCKET, SO_SNDTIMEO, &limit, sizeof limit));
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-reinterpret-cast): the sockets API takes sockaddr*.
  if (::connect(fd.get(), reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
    const int error = errno;
    if (error == EAGAIN || error == EINPROGRESS) {
      throw ControlClientError(where + ": no answer within " + seconds(timeout));
    }
    throw ControlClientError(where + ": " + detail::errno_text(error));
  }
  const int flags = ::fcntl(fd.get(), F_GETFL);
  if (flags < 0 || ::fcntl(fd.get(), F_SETFL, flags | O_NONBLOCK) != 0) {
    throw ControlClientError(where + ": " + detail::errno_text(errno));
  }
  fd_ = fd.release();
}

ControlClient::ControlClient(ControlClient&& other) noexcept
    : path_(std::move(other.path_)),
      timeout_(other.timeout_),
      fd_(std::exchange(other.fd_, -1)),
      buffer_(std::move(other.buffer_)) {}

ControlClient& ControlClient::operator=(ControlClient&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    path_ = std::move(other.path_);
    timeout_ = other.timeout_;
    fd_ = std::exchange(other.fd_, -1);
    buffer_ = std::move(other.buffer_);
  }
  return *this;
}

ControlClient::~ControlClient() {
  if (fd_ >= 0) ::close(fd_);
}

void ControlClient::wait_for(short events, Clock::time_point deadline, const char* what) {
  for (;;) {
    const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0) {
      throw ControlClientError(std::string("no ") + what + " " + path_.string() + " within " +
                               seconds(timeout_));
    }
    pollfd watched{fd_, events, 0};
    const int ready = ::poll(&watched, 1, static_cast<int>(std::min<std::int64_t>(left, INT_MAX)));
    if (ready > 0) return;
    if (ready < 0 && errno != EINTR) {
      throw ControlClientError("poll on " + path_.string() + ": " + detail::errno_text(errno));
    }
  }
}

void ControlClient::send(std::string_view bytes) {
  const Clock::time_point deadline = Clock::now() + timeout_;
  while (!bytes.empty()) {
    const ssize_t put = ::send(fd_, bytes.data(), bytes.size(), MSG_NOSIGNAL);
    if (put >= 0) {
      bytes.remove_prefix(static_cast<std::size_t>(put));
      continue;
    }
    const int error = errno;
    if (error == EINTR) continue;
    if (error != EAGAIN && error != EWOULDBLOCK) {
      throw ControlClientError("cannot send to " + path_.string() + ": " +
                               detail::errno_text(error));
    }
    wait_for(POLLOUT, deadline, "room to send to");
  }
}

std::string ControlClient::receive_line() {
  const Clock::time_point deadline = Clock::now() + timeout_;
  std::array<char, 4096> chunk{};
  for (;;) {
    const std::size_t newline = buffer_.find('\n');
    if (newline != std::string::npos) {
      std::string line = buffer_.substr(0, newline);
      buffer_.erase(0, newline + 1);
      return line;
    }
    if (buffer_.size() > kMaxReplyBytes) {
      throw ControlClientError("reply from " + path_.string() + " exceeds " +
                               std::to_string(kMaxReplyBytes) + " bytes");
    }
    const ssize_t got = ::recv(fd_, chunk.data(), chunk.size(), 0);
    if (got > 0) {
      buffer_.append(chunk.data(), static_cast<std::size_t>(got));
      continue;
    }
    if (got == 0) throw ControlClientError("the daemon closed the connection at " + path_.string());
    const int error = errno;
    if (error == EINTR) continue;
    if (error != EAGAIN && error != EWOULDBLOCK) {
      throw ControlClientError("cannot read from " + path_.string() + ": " +
                               detail::errno_text(error));
    }
    wait_for(POLLIN, deadline, "reply from");
  }
}

std::string ControlClient::exchange(std::string_view request) {
  std::string line(request);
  line += '\n';
  send(line);
  return receive_line();
}

}  // namespace selfsense::daemon
