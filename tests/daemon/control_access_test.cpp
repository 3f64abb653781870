// Who may connect: the kernel refuses a client outside the socket's group (mode 0660), and
// lets in one that is in it. Needs root to become `nobody` in a forked child; skipped
// otherwise.
#include <grp.h>
#include <gtest/gtest.h>
#include <pwd.h>
#include <sys/wait.h>

#include <string>

#include "daemon/server_support.hpp"
#include "selfsense/daemon/control_server.hpp"

namespace selfsense::daemon {
namespace {

constexpr int kConnected = 0;
constexpr int kRefused = 1;  // EACCES
constexpr int kOther = 2;

// Forks a child that drops every privilege to uid `uid` with only group `gid`, then tries to
// connect. Only system calls run in the child (the parent has threads).
int connect_as(uid_t uid, gid_t gid, const std::filesystem::path& path) {
  const pid_t child = ::fork();
  if (child == 0) {
    if (::setgroups(0, nullptr) != 0 || ::setresgid(gid, gid, gid) != 0 ||
        ::setresuid(uid, uid, uid) != 0) {
      ::_exit(kOther);
    }
    const int fd = test::connect_raw(path);
    ::_exit(fd >= 0 ? kConnected : (fd == -EACCES ? kRefused : kOther));
  }
  int status = 0;
  if (child < 0 || ::waitpid(child, &status, 0) != child || !WIFEXITED(status)) return -1;
  return WEXITSTATUS(status);
}

struct Identities {
  uid_t nobody{0};
  gid_t nogroup{0};
  gid_t daemon{0};
};

// getpwnam/getgrnam return a static buffer that the next call overwrites: copied at once.
bool look_up(Identities* ids) {
  const passwd* user = ::getpwnam("nobody");
  if (user == nullptr) return false;
  ids->nobody = user->pw_uid;
  const group* outside = ::getgrnam("nogroup");
  if (outside == nullptr) return false;
  ids->nogroup = outside->gr_gid;
  const group* inside = ::getgrnam("daemon");
  if (inside == nullptr) return false;
  ids->daemon = inside->gr_gid;
  return true;
}

TEST(ControlAccess, AClientOutsideTheGroupIsRefusedByTheKernel) {
  if (::geteuid() != 0) GTEST_SKIP() << "needs root to become nobody in a child";
  Identities ids;
  if (!look_up(&ids)) GTEST_SKIP() << "needs the user nobody and the groups nogroup and daemon";

  test::TempDir dir;  // mode 0755: only the socket's own mode decides
  test::FakeHandler handler;
  ControlServerConfig config;
  config.path = dir.socket();
  config.group = "daemon";
  ControlServer server(config, handler);
  server.start();

  EXPECT_EQ(connect_as(ids.nobody, ids.nogroup, dir.socket()), kRefused);
  EXPECT_EQ(connect_as(ids.nobody, ids.daemon, dir.socket()), kConnected);
  EXPECT_TRUE(test::eventually([&] { return server.counters().accepted == 1; }));
}

}  // namespace
}  // namespace selfsense::daemon
