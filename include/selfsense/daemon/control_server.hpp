// The control socket's server: a Unix domain stream socket served by its own thread (never the
// real-time one), speaking the protocol of control_protocol.hpp (docs/control-socket.md).
//
// start() creates the socket file with mode 0660 and the configured group before it listens,
// so no client ever sees wider permissions: it binds a temporary name in the same directory,
// sets mode and group, renames it onto the path and only then listens. A stale socket file
// (nobody answers) is replaced; a live one (another daemon answers) or a file that is not a
// socket makes start() fail. stop() closes every connection and removes the socket file (if it
// is still ours).
//
// One thread, poll(), non-blocking I/O, many clients. Each complete line is parsed against
// the handler's limits(); a valid request goes to handle() and its reply is written back, an
// invalid one gets the parse error; both in the order the lines came. Blank lines are ignored,
// a trailing "\r" is dropped, and a last line without newline is answered when the client
// half-closes. Bounds, so that no client can stall the others or grow memory:
//   - a line longer than max_line_bytes: an error reply, then the client is closed;
//   - replies the client does not read beyond max_output_bytes: the client is dropped;
//   - more than max_clients connections: the extra one gets an error line and is closed;
//   - no bytes either way for idle_timeout: an error line, then the client is closed;
//   - each client is read one chunk per poll round, so a flood takes turns with the others.
// Counters are atomics, readable from any thread (the daemon's status).
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "selfsense/daemon/control_protocol.hpp"

namespace selfsense::daemon {

// Who is at the other end of a connection, from the kernel (SO_PEERCRED) at accept time.
struct PeerCredentials {
  std::int64_t pid{0};
  std::uint32_t uid{0};
  std::uint32_t gid{0};
};

// What the daemon plugs into the server. Both methods run on the server thread, one call at a
// time; they must be quick (the daemon hands requests to the loop through its lock-free
// boxes) and never run on the real-time thread. Invalid requests never reach handle().
class RequestHandler {
 public:
  RequestHandler() = default;
  RequestHandler(const RequestHandler&) = delete;
  RequestHandler& operator=(const RequestHandler&) = delete;
  RequestHandler(RequestHandler&&) = delete;
  RequestHandler& operator=(RequestHandler&&) = delete;
  virtual ~RequestHandler() = default;

  // The limits a request is validated against now (the active mode picks the setpoint range).
  [[nodiscard]] virtual RequestLimits limits() = 0;
  // Carries out a valid request; returns the reply object, which must hold "ok" (ok_reply(),
  // error_reply()). An exception becomes an "internal error" reply.
  virtual nlohmann::json handle(const Request& request, const PeerCredentials& peer) = 0;
};

struct ControlServerConfig {
  std::filesystem::path path{"/run/selfsensed/control.sock"};
  std::string group{};  // owner group of the socket file, by name; empty: the process's group
  std::size_t max_clients{16};
  std::size_t max_line_bytes{std::size_t{64} * 1024};     // a request line without its newline
  std::size_t max_output_bytes{std::size_t{256} * 1024};  // unread replies kept per client
  std::chrono::milliseconds idle_timeout{std::chrono::minutes(5)};  // 0: never

  // False, with the violated constraint in *why.
  [[nodiscard]] bool is_valid(std::string* why) const;
};

// A snapshot of the server's counts since start().
struct ControlServerCounters {
  std::uint64_t accepted{0};        // connections served
  std::uint64_t refused{0};         // connections turned away (max_clients)
  std::uint64_t requests{0};        // request lines answered
  std::uint64_t rejected{0};        // of those, refused by the protocol (parse, limits)
  std::uint64_t errors{0};          // of those, replies with "ok": false (rejected included)
  std::uint64_t oversize_lines{0};  // lines over max_line_bytes (the client was closed)
  std::uint64_t dropped_slow{0};    // clients dropped for not reading their replies
  std::uint64_t idle_closed{0};     // clients closed after idle_timeout
  std::uint64_t clients{0};         // connected now
};

// Receives one line per event worth keeping (connections with their credentials, refusals,
// drops); called on the server thread.
using ControlServerLog = std::function<void(std::string_view)>;

class ControlServer final {
 public:
  // Throws std::invalid_argument when the configuration is invalid. The handler must outlive
  // the server.
  ControlServer(ControlServerConfig config, RequestHandler& handler, ControlServerLog log = {});
  ControlServer(const ControlServer&) = delete;
  ControlServer& operator=(const ControlServer&) = delete;
  ControlServer(ControlServer&&) = delete;
  ControlServer& operator=(ControlServer&&) = delete;
  ~ControlServer();  // stop()

  // Creates the socket and starts the thread. Throws std::runtime_error naming the path or the
  // group and the cause ("control socket group 'piezo' does not exist").
  void start();
  // Closes every connection, ends the thread and removes the socket file. Idempotent.
  void stop() noexcept;

  [[nodiscard]] bool running() const noexcept;
  [[nodiscard]] ControlServerCounters counters() const noexcept;
  [[nodiscard]] const ControlServerConfig& config() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace selfsense::daemon
