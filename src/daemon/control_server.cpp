#include "selfsense/daemon/control_server.hpp"

#include <poll.h>
#include <pthread.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <climits>
#include <stdexcept>
#include <thread>
#include <utility>
#include <vector>

#include "connection.hpp"
#include "unix_socket.hpp"

namespace selfsense::daemon {
namespace {

using detail::Connection;
using Clock = Connection::Clock;

constexpr std::size_t kChunk = std::size_t{16} * 1024;  // bytes read per client per poll round
constexpr int kBacklog = 16;
// Longest temporary-name suffix listen_at() appends (".new." and a pid).
constexpr std::size_t kTemporarySuffix = 16;
// When the process is out of file descriptors the listener stays readable; it is left alone
// this long instead of spinning on accept().
constexpr std::chrono::milliseconds kAcceptPause{100};

std::string who(const Connection& client) {
  const PeerCredentials& p = client.peer();
  return "client " + std::to_string(client.id()) + " (pid " + std::to_string(p.pid) + ", uid " +
         std::to_string(p.uid) + ", gid " + std::to_string(p.gid) + ")";
}

bool blank(std::string_view line) {
  return std::all_of(line.begin(), line.end(), [](char c) { return c == ' ' || c == '\t'; });
}

void bump(std::atomic<std::uint64_t>& counter) {
  counter.fetch_add(1, std::memory_order_relaxed);
}

}  // namespace

bool ControlServerConfig::is_valid(std::string* why) const {
  const auto fail = [why](const std::string& message) {
    if (why != nullptr) *why = "Violated constraint: ControlServerConfig." + message;
    return false;
  };
  const std::size_t room = sizeof(sockaddr_un::sun_path) - 1 - kTemporarySuffix;
  if (path.empty() || path.native().size() > room) {
    return fail("path: 1 to " + std::to_string(room) + " bytes (" + path.string() + ")");
  }
  if (max_clients < 1) return fail("max_clients >= 1");
  if (max_line_bytes < 256) return fail("max_line_bytes >= 256");
  if (max_output_bytes < 4096) return fail("max_output_bytes >= 4096");
  if (idle_timeout.count() < 0) return fail("idle_timeout >= 0");
  return true;
}

struct ControlServer::Impl {
  Impl(ControlServerConfig server_config, RequestHandler& request_handler, ControlServerLog sink)
      : config(std::move(server_config)), handler(request_handler), log(std::move(sink)) {}

  void run() noexcept;
  [[nodiscard]] int poll_timeout(Clock::time_point now) const;
  void accept_all(Clock::time_point now);
  void serve(Connection& client, Clock::time_point now);
  void answer(Connection& client, const std::string& line);
  void close_idle(Clock::time_point now);
  void note(const std::string& message) const {
    if (log) log(message);
  }

  ControlServerConfig config;
  RequestHandler& handler;
  ControlServerLog log;

  detail::ListeningSocket listener{};
  detail::Fd wake{};
  std::thread thread{};
  std::atomic<bool> stop_requested{false};
  std::atomic<bool> serving{false};

  std::atomic<std::uint64_t> accepted{0};
  std::atomic<std::uint64_t> refused{0};
  std::atomic<std::uint64_t> requests{0};
  std::atomic<std::uint64_t> rejected{0};
  std::atomic<std::uint64_t> errors{0};
  std::atomic<std::uint64_t> oversize_lines{0};
  std::atomic<std::uint64_t> dropped_slow{0};
  std::atomic<std::uint64_t> idle_closed{0};
  std::atomic<std::uint64_t> connected{0};

  // Server thread only.
  std::vector<Connection> clients{};
  std::uint64_t next_id{1};
  Clock::time_point accept_paused_until{};
};

void ControlServer::Impl::run() noexcept {
  ::pthread_setname_np(::pthread_self(), "selfsense-ctl");
  std::vector<pollfd> fds;
  try {
    while (!stop_requested.load(std::memory_order_acquire)) {
      Clock::time_point now = Clock::now();
      fds.clear();
      fds.push_back({wake.get(), POLLIN, 0});
      const bool listening = now >= accept_paused_until;
      fds.push_back({listening ? listener.fd.get() : -1, POLLIN, 0});
      for (const Connection& client : clients) {
        const auto events =
            static_cast<short>((client.closing ? 0 : POLLIN) | (client.unsent() > 0 ? POLLOUT : 0));
        fds.push_back({client.fd(), events, 0});
      }
      if (::poll(fds.data(), fds.size(), poll_timeout(now)) < 0 && errno != EINTR) {
        note("control: poll failed: " + detail::errno_text(errno) + "; the server stops");
        break;
      }
      now = Clock::now();
      for (std::size_t i = 0; i < clients.size(); ++i) {
        Connection& client = clients[i];
        const short revents = fds[i + 2].revents;
        if (!client.closing && (revents & (POLLIN | POLLHUP | POLLERR)) != 0) serve(client, now);
        if (!client.dead && client.unsent() > 0 && !client.send(now)) client.dead = true;
      }
      if ((fds[1].revents & POLLIN) != 0) accept_all(now);
      close_idle(now);
      std::erase_if(clients, [](const Connection& client) {
        return client.dead || (client.closing && client.unsent() == 0);
      });
      connected.store(clients.size(), std::memory_order_relaxed);
    }
  } catch (const std::exception& e) {
    // Only allocation failure gets here; the daemon sees running() turn false.
    note(std::string("control: server thread stops: ") + e.what());
  }
  clients.clear();
  connected.store(0, std::memory_order_relaxed);
  serving.store(false, std::memory_order_release);
}

int ControlServer::Impl::poll_timeout(Clock::time_point now) const {
  std::optional<Clock::time_point> next;
  if (now < accept_paused_until) next = accept_paused_until;
  if (config.idle_timeout.count() > 0) {
    for (const Connection& client : clients) {
      const Clock::time_point due = client.last_active() + config.idle_timeout;
      if (!next || due < *next) next = due;
    }
  }
  if (!next) return -1;
  if (*next <= now) return 0;
  const auto wait = std::chrono::ceil<std::chrono::milliseconds>(*next - now).count();
  return static_cast<int>(std::min<std::int64_t>(wait, INT_MAX));
}

void ControlServer::Impl::accept_all(Clock::time_point now) {
  for (;;) {
    detail::Fd fd(::accept4(listener.fd.get(), nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC));
    if (!fd.valid()) {
      const int error = errno;
      if (error == EINTR || error == ECONNABORTED) continue;
      if (error != EAGAIN && error != EWOULDBLOCK) {
        note("control: accept failed: " + detail::errno_text(error));
        accept_paused_until = now + kAcceptPause;
      }
      return;
    }
    const PeerCredentials peer = detail::peer_of(fd.get()).value_or(PeerCredentials{-1, 0, 0});
    Connection client(std::move(fd), peer, next_id++, now);
    if (clients.size() >= config.max_clients) {
      bump(refused);
      note("control: " + who(client) + " refused: too many clients");
      client.queue(reply_line(error_reply(
          "too many clients (limit " + std::to_string(config.max_clients) + "); try again later")));
      static_cast<void>(client.send(now));  // best effort; the client is closed either way
      continue;
    }
    bump(accepted);
    note("control: " + who(client) + " connected");
    clients.push_back(std::move(client));
  }
}

void ControlServer::Impl::serve(Connection& client, Clock::time_point now) {
  const Connection::Read got = client.receive(kChunk, now);
  if (got == Connection::Read::kBroken) {
    client.dead = true;
    return;
  }
  const bool at_end = got == Connection::Read::kEnd;
  for (;;) {
    Connection::Line line = client.next_line(config.max_line_bytes, at_end);
    if (line.kind == Connection::Line::Kind::kNone) break;
    if (line.kind == Connection::Line::Kind::kTooLong) {
      bump(oversize_lines);
      bump(errors);
      note("control: " + who(client) + " sent a line over " +
           std::to_string(config.max_line_bytes) + " bytes; closing");
      client.queue(reply_line(error_reply("request line longer than " +
                                          std::to_string(config.max_line_bytes) +
                                          " bytes; closing the connection")));
      client.discard_input();
      client.closing = true;
      return;
    }
    if (blank(line.text)) continue;
    answer(client, line.text);
    if (client.unsent() > config.max_output_bytes) {
      if (!client.send(now)) {
        client.dead = true;
        return;
      }
      if (client.unsent() > config.max_output_bytes) {
        bump(dropped_slow);
        note("control: " + who(client) + " dropped: " + std::to_string(client.unsent()) +
             " bytes of replies unread");
        client.dead = true;
        return;
      }
    }
  }
  if (at_end) client.closing = true;
}

void ControlServer::Impl::answer(Connection& client, const std::string& line) {
  bump(requests);
  nlohmann::json reply;
  try {
    const ParsedRequest parsed = parse_request(line, handler.limits());
    if (parsed.request) {
      reply = handler.handle(*parsed.request, client.peer());
      const auto ok = reply.is_object() ? reply.find("ok") : reply.end();
      if (!reply.is_object() || ok == reply.end() || !ok->is_boolean()) {
        reply = error_reply("internal error: the daemon's reply has no \"ok\"");
      }
    } else {
      bump(rejected);
      reply = error_reply(parsed.error);
    }
  } catch (const std::exception& e) {
    note("control: handler failed for " + who(client) + ": " + e.what());
    reply = error_reply(std::string("internal error: ") + e.what());
  }
  if (!reply.at("ok").get<bool>()) bump(errors);
  client.queue(reply_line(reply));
}

void ControlServer::Impl::close_idle(Clock::time_point now) {
  if (config.idle_timeout.count() <= 0) return;
  for (Connection& client : clients) {
    if (client.dead || now - client.last_active() < config.idle_timeout) continue;
    bump(idle_closed);
    note("control: " + who(client) + " idle; closing");
    client.queue(reply_line(error_reply("idle for " + std::to_string(config.idle_timeout.count()) +
                                        " ms; closing the connection")));
    static_cast<void>(client.send(now));
    client.dead = true;
  }
}

ControlServer::ControlServer(ControlServerConfig config, RequestHandler& handler,
                             ControlServerLog log) {
  std::string why;
  if (!config.is_valid(&why)) throw std::invalid_argument(why);
  impl_ = std::make_unique<Impl>(std::move(config), handler, std::move(log));
}

ControlServer::~ControlServer() {
  stop();
}

void ControlServer::start() {
  Impl& s = *impl_;
  if (s.thread.joinable()) throw std::logic_error("ControlServer::start: already started");
  s.wake = detail::Fd(::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC));
  if (!s.wake.valid()) throw std::runtime_error("eventfd: " + detail::errno_text(errno));
  s.listener = detail::listen_at(s.config.path, s.config.group, kBacklog);
  for (auto* counter : {&s.accepted, &s.refused, &s.requests, &s.rejected, &s.errors,
                        &s.oversize_lines, &s.dropped_slow, &s.idle_closed, &s.connected}) {
    counter->store(0, std::memory_order_relaxed);
  }
  s.stop_requested.store(false, std::memory_order_release);
  s.serving.store(true, std::memory_order_release);
  s.thread = std::thread([&s] { s.run(); });
}

void ControlServer::stop() noexcept {
  if (!impl_ || !impl_->thread.joinable()) return;
  Impl& s = *impl_;
  s.stop_requested.store(true, std::memory_order_release);
  const std::uint64_t one = 1;
  static_cast<void>(::write(s.wake.get(), &one, sizeof one));
  s.thread.join();
  detail::remove_if_ours(s.config.path, s.listener.device, s.listener.inode);
  s.listener.fd.reset();
  s.wake.reset();
}

bool ControlServer::running() const noexcept {
  return impl_->serving.load(std::memory_order_acquire);
}

ControlServerCounters ControlServer::counters() const noexcept {
  const Impl& s = *impl_;
  const auto read = [](const std::atomic<std::uint64_t>& counter) {
    return counter.load(std::memory_order_relaxed);
  };
  return {read(s.accepted),     read(s.refused),     read(s.requests),
          read(s.rejected),     read(s.errors),      read(s.oversize_lines),
          read(s.dropped_slow), read(s.idle_closed), read(s.connected)};
}

const ControlServerConfig& ControlServer::config() const noexcept {
  return impl_->config;
}

}  // namespace selfsense::daemon
