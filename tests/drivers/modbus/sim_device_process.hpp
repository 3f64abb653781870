// `selfsense sim-device` as a child process for the Modbus tests and the benchmark: started
// with a plant, a rate and the bus options, waited for until it prints its first line (which
// names the bound TCP port), stopped by a signal with its exit status returned.
#pragma once

#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <csignal>
#include <stdexcept>
#include <string>
#include <vector>

namespace selfsense::test {

// `selfsense sim-device` as a child process; its first line names the bound port.
class SimDeviceProcess {
 public:
  SimDeviceProcess(const std::string& cli, const std::string& plant, double rate_hz,
                   const std::vector<std::string>& bus_args) {
    std::array<int, 2> out{};
    if (pipe(out.data()) != 0) throw std::runtime_error("pipe");
    pid_ = fork();
    if (pid_ == 0) {
      dup2(out[1], STDOUT_FILENO);
      close(out[0]);
      std::vector<std::string> args{"selfsense", "sim-device", "--plant",
                                    plant,       "--rate",     std::to_string(rate_hz)};
      args.insert(args.end(), bus_args.begin(), bus_args.end());
      std::vector<char*> argv;
      argv.reserve(args.size() + 1);
      for (std::string& a : args)
        argv.push_back(a.data());
      argv.push_back(nullptr);
      execv(cli.c_str(), argv.data());
      _exit(127);
    }
    close(out[1]);
    out_ = out[0];
    std::string line;
    pollfd p{out_, POLLIN, 0};
    while (line.find('\n') == std::string::npos && poll(&p, 1, 10000) > 0) {
      std::array<char, 256> buf{};
      const ssize_t n = ::read(out_, buf.data(), buf.size());
      if (n <= 0) break;
      line.append(buf.data(), static_cast<std::size_t>(n));
    }
    if (line.find("sim-device: modbus-") == std::string::npos) {
      throw std::runtime_error("sim-device did not start: '" + line + "'");
    }
    const std::size_t colon = line.find("127.0.0.1:");
    if (colon != std::string::npos) port_ = std::stoi(line.substr(colon + 10));
  }
  SimDeviceProcess(const SimDeviceProcess&) = delete;
  SimDeviceProcess& operator=(const SimDeviceProcess&) = delete;
  SimDeviceProcess(SimDeviceProcess&&) = delete;
  SimDeviceProcess& operator=(SimDeviceProcess&&) = delete;
  virtual ~SimDeviceProcess() {
    if (pid_ > 0) static_cast<void>(stop(SIGKILL));
    close(out_);
  }
  [[nodiscard]] int port() const { return port_; }
  void signal(int s) const { kill(pid_, s); }
  // The exit status (or 128 + signal).
  int stop(int s = SIGTERM) {
    kill(pid_, SIGCONT);
    kill(pid_, s);
    int status = 0;
    waitpid(pid_, &status, 0);
    pid_ = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }

 private:
  pid_t pid_{-1};
  int out_{-1};
  int port_{0};
};

}  // namespace selfsense::test
