// selfsensed as a child process of a test (the soak test, the crash and reload tests): started
// with its configuration, stdout and stderr in files, signalled, its resident memory read from
// /proc, waited for.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <optional>

namespace selfsense::test {

class DaemonProcess final {
 public:
  // Starts `selfsensed --config CONFIG`, output to LOG.out and LOG.err. Throws on failure.
  DaemonProcess(const std::filesystem::path& selfsensed, const std::filesystem::path& config,
                const std::filesystem::path& log);
  DaemonProcess(const DaemonProcess&) = delete;
  DaemonProcess& operator=(const DaemonProcess&) = delete;
  DaemonProcess(DaemonProcess&&) = delete;
  DaemonProcess& operator=(DaemonProcess&&) = delete;
  ~DaemonProcess();  // SIGKILL and reap when still running

  [[nodiscard]] pid_t pid() const noexcept { return pid_; }
  void signal(int sig) const;
  // VmRSS [bytes]; nullopt once the process is gone.
  [[nodiscard]] std::optional<std::uint64_t> rss_bytes() const;
  // The exit status (or 128 + signal) once it exited within the timeout; nullopt otherwise.
  // Once it returned a value, further calls give the same.
  std::optional<int> wait(std::chrono::milliseconds timeout);
  [[nodiscard]] bool running() const noexcept { return !exit_status_.has_value(); }

 private:
  pid_t pid_{-1};
  std::optional<int> exit_status_{};
};

}  // namespace selfsense::test
