// The real selfsensed as a child process for tests that crash, signal and reload it: a scratch
// configuration derived from config/sim.yaml (the shipped example, so the test follows it), the
// process started with its output in a log file, requests over its control socket, kill -9,
// SIGHUP and SIGTERM.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "selfsense/daemon/control_client.hpp"

namespace selfsense::daemon::testing {

inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

inline void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::trunc);
  out << text;
  if (!out.flush()) throw std::runtime_error("cannot write " + path.string());
}

// config/sim.yaml with the model, socket and telemetry in `dir`, the recordings in `recordings`
// (default dir/recordings), and the replacements given (each `from` must occur: a changed
// example fails the test loudly).
inline std::string scratch_config(const std::filesystem::path& dir,
                                  const std::vector<std::pair<std::string, std::string>>& changes,
                                  std::filesystem::path recordings = {}) {
  if (recordings.empty()) recordings = dir / "recordings";
  const std::filesystem::path source = SELFSENSE_SOURCE_DIR;
  std::string text = read_text(source / "config" / "sim.yaml");
  std::vector<std::pair<std::string, std::string>> all = {
      {"model: models/sim.yaml", "model: " + (dir / "model.yaml").string()},
      {"plant: plant/daemon.yaml",
       "plant: " + (source / "config" / "plant" / "daemon.yaml").string()},
      {"directory: ../build/sim/recordings", "directory: " + recordings.string()},
      {"path: ../build/sim/control.sock", "path: " + (dir / "control.sock").string()},
      {"prometheus_file: ../build/sim/selfsensed.prom",
       "prometheus_file: " + (dir / "selfsensed.prom").string()},
  };
  all.insert(all.end(), changes.begin(), changes.end());
  for (const auto& [from, to] : all) {
    const std::size_t at = text.find(from);
    if (at == std::string::npos) throw std::runtime_error("config/sim.yaml has no '" + from + "'");
    text.replace(at, from.size(), to);
  }
  return text;
}

class DaemonProcess final {
 public:
  // Starts selfsensed --config `config`; output to `log`. Waits until its socket answers.
  DaemonProcess(const std::filesystem::path& config, std::filesystem::path socket,
                std::filesystem::path log)
      : socket_(std::move(socket)), log_(std::move(log)) {
    pid_ = ::fork();
    if (pid_ < 0) throw std::runtime_error("fork failed");
    if (pid_ == 0) {
      const int out = ::open(log_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
      if (out >= 0) {
        ::dup2(out, STDOUT_FILENO);
        ::dup2(out, STDERR_FILENO);
      }
      ::execl(SELFSENSED_BINARY, "selfsensed", "--config", config.c_str(),
              static_cast<char*>(nullptr));
      ::_exit(127);
    }
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (std::chrono::steady_clock::now() < deadline) {
      if (exited()) throw std::runtime_error("selfsensed exited at start: " + read_text(log_));
      try {
        if (request(R"({"request": "status"})").value("ok", false)) return;
      } catch (const ControlClientError&) {
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    throw std::runtime_error("selfsensed did not answer within 30 s: " + read_text(log_));
  }
  DaemonProcess(const DaemonProcess&) = delete;
  DaemonProcess& operator=(const DaemonProcess&) = delete;
  DaemonProcess(DaemonProcess&&) = delete;
  DaemonProcess& operator=(DaemonProcess&&) = delete;
  ~DaemonProcess() {
    if (pid_ > 0) static_cast<void>(kill_hard());
  }

  // One request line; the parsed reply. Throws ControlClientError when the socket fails.
  nlohmann::json request(const std::string& line) {
    ControlClient client(socket_, std::chrono::milliseconds(3000));
    return nlohmann::json::parse(client.exchange(line));
  }
  nlohmann::json status() { return request(R"({"request": "status"})"); }

  void signal(int sig) const { ::kill(pid_, sig); }
  // kill -9 and reap; returns the wait status.
  int kill_hard() {
    ::kill(pid_, SIGKILL);
    return reap();
  }
  // SIGTERM and the exit status (-1: did not exit normally).
  int terminate() {
    ::kill(pid_, SIGTERM);
    const int status = reap();
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  [[nodiscard]] std::string log() const { return read_text(log_); }

 private:
  bool exited() {
    int status = 0;
    if (::waitpid(pid_, &status, WNOHANG) == pid_) {
      pid_ = -1;
      return true;
    }
    return false;
  }
  int reap() {
    int status = 0;
    while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
    pid_ = -1;
    return status;
  }

  std::filesystem::path socket_;
  std::filesystem::path log_;
  pid_t pid_{-1};
};

}  // namespace selfsense::daemon::testing
