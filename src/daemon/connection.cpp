#include "connection.hpp"

#include <sys/socket.h>

#include <cerrno>
#include <utility>

namespace selfsense::daemon::detail {

Connection::Connection(Fd fd, PeerCredentials peer, std::uint64_t id, Clock::time_point now)
    : fd_(std::move(fd)), peer_(peer), id_(id), last_active_(now) {}

Connection::Read Connection::receive(std::size_t chunk, Clock::time_point now) {
  // Whole lines already handed out are dropped here, not per line, to copy once per chunk.
  in_.erase(0, consumed_);
  consumed_ = 0;
  const std::size_t old_size = in_.size();
  in_.resize(old_size + chunk);
  const ssize_t got = ::recv(fd_.get(), in_.data() + old_size, chunk, MSG_DONTWAIT);
  const int error = errno;
  in_.resize(old_size + (got > 0 ? static_cast<std::size_t>(got) : 0));
  if (got > 0) {
    last_active_ = now;
    return Read::kData;
  }
  if (got == 0) return Read::kEnd;
  if (error == EAGAIN || error == EWOULDBLOCK || error == EINTR) return Read::kNothing;
  return Read::kBroken;
}

Connection::Line Connection::next_line(std::size_t max_bytes, bool at_end) {
  const std::string_view pending = std::string_view(in_).substr(consumed_);
  const std::size_t newline = pending.find('\n');
  if (newline == std::string_view::npos) {
    if (pending.size() > max_bytes) return {Line::Kind::kTooLong, {}};
    if (!at_end || pending.empty()) return {Line::Kind::kNone, {}};
  }
  const std::size_t length = newline == std::string_view::npos ? pending.size() : newline;
  if (length > max_bytes) return {Line::Kind::kTooLong, {}};
  std::string_view line = pending.substr(0, length);
  consumed_ += newline == std::string_view::npos ? length : length + 1;
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  return {Line::Kind::kLine, std::string(line)};
}

void Connection::discard_input() noexcept {
  in_.clear();
  consumed_ = 0;
}

void Connection::queue(std::string_view bytes) {
  // Sent bytes are dropped once they are half the buffer, so memory stays within twice the
  // unsent bound however slowly the client reads.
  if (sent_ > 0 && 2 * sent_ >= out_.size()) {
    out_.erase(0, sent_);
    sent_ = 0;
  }
  out_.append(bytes);
}

bool Connection::send(Clock::time_point now) {
  while (sent_ < out_.size()) {
    const ssize_t put =
        ::send(fd_.get(), out_.data() + sent_, out_.size() - sent_, MSG_DONTWAIT | MSG_NOSIGNAL);
    if (put < 0) {
      if (errno == EINTR) continue;
      return errno == EAGAIN || errno == EWOULDBLOCK;
    }
    sent_ += static_cast<std::size_t>(put);
    last_active_ = now;
  }
  out_.clear();
  sent_ = 0;
  return true;
}

}  // namespace selfsense::daemon::detail
