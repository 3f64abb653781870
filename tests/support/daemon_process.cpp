#include "support/daemon_process.hpp"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <fstream>
#include <stdexcept>
#include <string>
#include <thread>

namespace selfsense::test {

DaemonProcess::DaemonProcess(const std::filesystem::path& selfsensed,
                             const std::filesystem::path& config,
                             const std::filesystem::path& log) {
  const std::string out = log.string() + ".out";
  const std::string err = log.string() + ".err";
  const std::string program = selfsensed.string();
  const std::string config_arg = config.string();
  pid_ = ::fork();
  if (pid_ < 0) throw std::runtime_error("fork failed");
  if (pid_ == 0) {
    const int out_fd = ::open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int err_fd = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (out_fd < 0 || err_fd < 0 || ::dup2(out_fd, STDOUT_FILENO) < 0 ||
        ::dup2(err_fd, STDERR_FILENO) < 0) {
      ::_exit(126);
    }
    // The test's signal mask is not the daemon's: it sets its own.
    sigset_t none;
    sigemptyset(&none);
    pthread_sigmask(SIG_SETMASK, &none, nullptr);
    const char* argv[] = {program.c_str(), "--config", config_arg.c_str(), nullptr};
    ::execv(program.c_str(), const_cast<char* const*>(argv));  // NOLINT: execv's signature
    ::_exit(127);
  }
}

DaemonProcess::~DaemonProcess() {
  if (running() && pid_ > 0) {
    ::kill(pid_, SIGKILL);
    static_cast<void>(wait(std::chrono::seconds(10)));
  }
}

void DaemonProcess::signal(int sig) const {
  if (running() && ::kill(pid_, sig) != 0) throw std::runtime_error("kill failed");
}

std::optional<std::uint64_t> DaemonProcess::rss_bytes() const {
  std::ifstream in("/proc/" + std::to_string(pid_) + "/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stoull(line.substr(6)) * 1024U;
  }
  return std::nullopt;
}

std::optional<int> DaemonProcess::wait(std::chrono::milliseconds timeout) {
  if (exit_status_) return exit_status_;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    int status = 0;
    const pid_t got = ::waitpid(pid_, &status, WNOHANG);
    if (got == pid_) {
      exit_status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      return exit_status_;
    }
    if (std::chrono::steady_clock::now() > deadline) return std::nullopt;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

}  // namespace selfsense::test
