#include "unix_socket.hpp"

#include <fcntl.h>
#include <grp.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <vector>

namespace selfsense::daemon::detail {
namespace {

constexpr mode_t kSocketMode = 0660;

[[noreturn]] void fail(const std::string& what, int error) {
  throw std::runtime_error(what + ": " + errno_text(error));
}

gid_t group_id(const std::string& name) {
  std::vector<char> buffer(std::size_t{16} * 1024);
  struct group entry {};
  for (;;) {
    struct group* found = nullptr;
    const int error = ::getgrnam_r(name.c_str(), &entry, buffer.data(), buffer.size(), &found);
    if (error == ERANGE && buffer.size() < (1U << 20U)) {
      buffer.resize(buffer.size() * 2);
      continue;
    }
    if (error != 0) fail("control socket group '" + name + "'", error);
    if (found == nullptr)
      throw std::runtime_error("control socket group '" + name + "' does not exist");
    return found->gr_gid;
  }
}

// Whether a daemon answers at an existing socket file: a refused connection means a stale
// file left by a process that died.
bool answers(const std::filesystem::path& path) {
  const Fd probe(::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0));
  if (!probe.valid()) fail("socket", errno);
  sockaddr_un address{};
  try {
    address = address_of(path);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error("control socket " + path.string() + ": " + e.what());
  }
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-reinterpret-cast): the sockets API takes sockaddr*.
  if (::connect(probe.get(), reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0) {
    return true;
  }
  const int error = errno;
  if (error == ECONNREFUSED) return false;
  if (error == EAGAIN) return true;  // a listener whose backlog is full is alive
  fail("control socket " + path.string() + ": cannot tell whether a daemon answers there", error);
}

void clear_path(const std::filesystem::path& path) {
  struct stat info {};
  if (::lstat(path.c_str(), &info) != 0) {
    if (errno == ENOENT) return;
    fail("control socket " + path.string(), errno);
  }
  if (!S_ISSOCK(info.st_mode)) {
    throw std::runtime_error("control socket " + path.string() +
                             ": exists and is not a socket; refusing to replace it");
  }
  if (answers(path)) {
    throw std::runtime_error("control socket " + path.string() +
                             ": another daemon answers there; refusing to start");
  }
  if (::unlink(path.c_str()) != 0 && errno != ENOENT) {
    fail("control socket " + path.string() + ": cannot remove the stale socket file", errno);
  }
}

}  // namespace

Fd& Fd::operator=(Fd&& other) noexcept {
  if (this != &other) {
    reset();
    fd_ = other.release();
  }
  return *this;
}

int Fd::release() noexcept {
  const int fd = fd_;
  fd_ = -1;
  return fd;
}

void Fd::reset() noexcept {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

sockaddr_un address_of(const std::filesystem::path& path) {
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  const std::string& text = path.native();
  if (text.empty() || text.size() >= sizeof address.sun_path) {
    throw std::runtime_error("a socket path has 1 to " +
                             std::to_string(sizeof address.sun_path - 1) + " bytes");
  }
  std::memcpy(&address.sun_path[0], text.data(), text.size());
  return address;
}

ListeningSocket listen_at(const std::filesystem::path& path, const std::string& group,
                          int backlog) {
  const gid_t gid = group.empty() ? ::getegid() : group_id(group);
  clear_path(path);

  // Mode and group are set on a temporary name that nobody can connect to (no listen yet),
  // then the file is renamed onto the path: clients only ever see the final permissions.
  std::filesystem::path temporary = path;
  temporary += ".new." + std::to_string(::getpid());
  ListeningSocket out;
  out.fd = Fd(::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0));
  if (!out.fd.valid()) fail("socket", errno);
  sockaddr_un address{};
  try {
    address = address_of(temporary);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error("control socket " + path.string() + ": " + e.what());
  }
  ::unlink(temporary.c_str());  // left by a crash of this same pid number; ours to remove
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-reinterpret-cast): the sockets API takes sockaddr*.
  if (::bind(out.fd.get(), reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
    fail("cannot create control socket " + path.string(), errno);
  }
  const auto undo = [&temporary](const std::string& what, int error) {
    ::unlink(temporary.c_str());
    fail(what, error);
  };
  if (::chmod(temporary.c_str(), kSocketMode) != 0) undo("chmod " + temporary.string(), errno);
  if (!group.empty() && ::chown(temporary.c_str(), static_cast<uid_t>(-1), gid) != 0) {
    undo("cannot give control socket " + path.string() + " to group '" + group + "'", errno);
  }
  if (::rename(temporary.c_str(), path.c_str()) != 0)
    undo("cannot create control socket " + path.string(), errno);
  struct stat info {};
  if (::lstat(path.c_str(), &info) != 0) fail("control socket " + path.string(), errno);
  out.device = info.st_dev;
  out.inode = info.st_ino;
  if (::listen(out.fd.get(), backlog) != 0) {
    remove_if_ours(path, out.device, out.inode);
    fail("listen on control socket " + path.string(), errno);
  }
  return out;
}

void remove_if_ours(const std::filesystem::path& path, dev_t device, ino_t inode) noexcept {
  struct stat info {};
  if (::lstat(path.c_str(), &info) == 0 && info.st_dev == device && info.st_ino == inode) {
    ::unlink(path.c_str());
  }
}

std::optional<PeerCredentials> peer_of(int fd) noexcept {
  ucred credentials{};
  socklen_t size = sizeof credentials;
  if (::getsockopt(fd, SOL_SOCKET, SO_PEERCRED, &credentials, &size) != 0) return std::nullopt;
  return PeerCredentials{credentials.pid, credentials.uid, credentials.gid};
}

}  // namespace selfsense::daemon::detail
