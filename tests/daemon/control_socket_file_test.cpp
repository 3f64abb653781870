// The socket file: mode 0660 and group, stale and live sockets at the path, and the errors
// that name what is wrong.
#include <grp.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <fstream>
#include <string>

#include "daemon/server_support.hpp"
#include "selfsense/daemon/control_client.hpp"
#include "selfsense/daemon/control_server.hpp"

namespace selfsense::daemon {
namespace {

using std::chrono::milliseconds;

std::string start_error(ControlServer& server) {
  try {
    server.start();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "started";
}

// A group the socket can be given: as root one that is not ours ("daemon"), else our own.
std::string some_group() {
  if (::geteuid() == 0 && ::getgrnam("daemon") != nullptr) return "daemon";
  const group* own = ::getgrgid(::getegid());
  return own != nullptr ? own->gr_name : "";
}

class ControlSocketFileTest : public ::testing::Test {
 protected:
  ControlServerConfig config(const std::string& group = "") const {
    ControlServerConfig c;
    c.path = dir.socket();
    c.group = group;
    return c;
  }
  [[nodiscard]] bool dir_holds_only(const std::vector<std::string>& names) const {
    std::vector<std::string> found;
    for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
      found.push_back(entry.path().filename().string());
    }
    std::sort(found.begin(), found.end());
    return found == names;
  }

  test::TempDir dir;
  test::FakeHandler handler;
};

TEST_F(ControlSocketFileTest, ModeIs0660AndTheGroupIsTheConfiguredOne) {
  const std::string group = some_group();
  ASSERT_FALSE(group.empty());
  ControlServer server(config(group), handler);
  server.start();
  struct stat info {};
  ASSERT_EQ(::stat(dir.socket().c_str(), &info), 0);
  EXPECT_TRUE(S_ISSOCK(info.st_mode));
  EXPECT_EQ(info.st_mode & 07777, 0660U);
  EXPECT_EQ(info.st_gid, ::getgrnam(group.c_str())->gr_gid);
  EXPECT_EQ(info.st_uid, ::geteuid());
  EXPECT_TRUE(dir_holds_only({"control.sock"}));  // no temporary name left behind
}

TEST_F(ControlSocketFileTest, ModeIs0660WhateverTheUmask) {
  const mode_t old = ::umask(0);
  ControlServer server(config(), handler);
  server.start();
  ::umask(old);
  struct stat info {};
  ASSERT_EQ(::stat(dir.socket().c_str(), &info), 0);
  EXPECT_EQ(info.st_mode & 07777, 0660U);
  EXPECT_EQ(info.st_gid, ::getegid());
}

TEST_F(ControlSocketFileTest, AnUnknownGroupIsNamedAndNothingIsCreated) {
  ControlServer server(config("no-such-group-selfsense"), handler);
  EXPECT_EQ(start_error(server), "control socket group 'no-such-group-selfsense' does not exist");
  EXPECT_FALSE(server.running());
  EXPECT_TRUE(dir_holds_only({}));
}

TEST_F(ControlSocketFileTest, AStaleSocketFileIsReplaced) {
  {
    // A socket file nobody listens on, as a crashed daemon leaves it.
    const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
    const sockaddr_un address = test::unix_address(dir.socket());
    // NOLINTNEXTLINE(cppcoreguidelines-pro-type-reinterpret-cast): the sockets API takes sockaddr*.
    ASSERT_EQ(::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address), 0);
    ::close(fd);
  }
  ASSERT_TRUE(std::filesystem::is_socket(dir.socket()));
  ControlServer server(config(), handler);
  server.start();
  EXPECT_EQ(ControlClient(dir.socket(), milliseconds(5000)).exchange(R"({"request":"arm"})"),
            R"({"ok":true})");
}

TEST_F(ControlSocketFileTest, ALiveDaemonAtThePathIsLeftAlone) {
  ControlServer first(config(), handler);
  first.start();
  ControlServer second(config(), handler);
  EXPECT_EQ(start_error(second), "control socket " + dir.socket().string() +
                                     ": another daemon answers there; refusing to start");
  EXPECT_EQ(ControlClient(dir.socket(), milliseconds(5000)).exchange(R"({"request":"arm"})"),
            R"({"ok":true})");
  second.stop();  // never started: must not remove the first one's socket
  EXPECT_TRUE(std::filesystem::is_socket(dir.socket()));
}

TEST_F(ControlSocketFileTest, AFileThatIsNotASocketIsNeverReplaced) {
  std::ofstream(dir.socket()) << "precious\n";
  ControlServer server(config(), handler);
  EXPECT_EQ(start_error(server), "control socket " + dir.socket().string() +
                                     ": exists and is not a socket; refusing to replace it");
  std::ifstream in(dir.socket());
  std::string text;
  std::getline(in, text);
  EXPECT_EQ(text, "precious");
}

TEST_F(ControlSocketFileTest, AMissingDirectoryIsNamed) {
  ControlServerConfig c = config();
  c.path = dir.path() / "missing" / "control.sock";
  ControlServer server(c, handler);
  EXPECT_EQ(start_error(server),
            "cannot create control socket " + c.path.string() + ": No such file or directory");
}

TEST_F(ControlSocketFileTest, ConfigurationIsValidated) {
  ControlServerConfig c = config();
  c.path = "/tmp/" + std::string(100, 'x');
  std::string why;
  EXPECT_FALSE(c.is_valid(&why));
  EXPECT_EQ(why.rfind("Violated constraint: ControlServerConfig.path: 1 to 91 bytes", 0), 0U);
  EXPECT_THROW(ControlServer(c, handler), std::invalid_argument);
  c = config();
  c.max_clients = 0;
  EXPECT_FALSE(c.is_valid(&why));
  EXPECT_EQ(why, "Violated constraint: ControlServerConfig.max_clients >= 1");
  c = config();
  c.idle_timeout = milliseconds(-1);
  EXPECT_FALSE(c.is_valid(&why));
  EXPECT_EQ(why, "Violated constraint: ControlServerConfig.idle_timeout >= 0");
}

}  // namespace
}  // namespace selfsense::daemon
