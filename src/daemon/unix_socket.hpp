// Unix domain socket plumbing shared by the control server and client: an owning file
// descriptor, addresses, the listening socket with its file mode and group, peer credentials.
// Private to the daemon library.
#pragma once

#include <sys/stat.h>
#include <sys/un.h>

#include <filesystem>
#include <optional>
#include <string>

#include "selfsense/base/errno_text.hpp"
#include "selfsense/daemon/control_server.hpp"

namespace selfsense::daemon::detail {

// Owns one file descriptor; closes it on destruction.
class Fd final {
 public:
  Fd() = default;
  explicit Fd(int fd) noexcept : fd_(fd) {}
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  Fd(Fd&& other) noexcept : fd_(other.release()) {}
  Fd& operator=(Fd&& other) noexcept;
  ~Fd() { reset(); }

  [[nodiscard]] int get() const noexcept { return fd_; }
  [[nodiscard]] bool valid() const noexcept { return fd_ >= 0; }
  int release() noexcept;
  void reset() noexcept;

 private:
  int fd_{-1};
};

// The text of an errno value (thread-safe).
using base::errno_text;

// The socket address of a path; throws std::runtime_error when the path does not fit.
[[nodiscard]] sockaddr_un address_of(const std::filesystem::path& path);

// A listening socket and the identity of its file, to remove only our own file at the end.
struct ListeningSocket {
  Fd fd{};
  dev_t device{0};
  ino_t inode{0};
};

// Creates the listening, non-blocking socket at path with mode 0660 and the group (empty:
// the process's), replacing a stale socket file. Throws std::runtime_error naming the path or
// group and the cause.
[[nodiscard]] ListeningSocket listen_at(const std::filesystem::path& path, const std::string& group,
                                        int backlog);

// Removes the socket file when it is still the one listen_at() made.
void remove_if_ours(const std::filesystem::path& path, dev_t device, ino_t inode) noexcept;

// The peer's pid, uid and gid as the kernel saw them at connect; nullopt when unavailable.
[[nodiscard]] std::optional<PeerCredentials> peer_of(int fd) noexcept;

}  // namespace selfsense::daemon::detail
