// A stand-in daemon for the `selfsense ctl` end-to-end test: serves the control socket at the
// given path with the test limits and replies ok with the request it understood, so the test
// sees exactly what the client sent. `mode` changes the active mode (and so the setpoint
// range). Runs until SIGTERM or SIGINT, then removes its socket.
#include <csignal>
#include <cstdio>
#include <exception>
#include <mutex>

#include "daemon/test_limits.hpp"
#include "selfsense/daemon/control_server.hpp"

namespace {

using namespace selfsense::daemon;

class EchoHandler final : public RequestHandler {
 public:
  RequestLimits limits() override {
    const std::lock_guard lock(mutex_);
    return test::limits(mode_);
  }
  nlohmann::json handle(const Request& request, const PeerCredentials& /*peer*/) override {
    if (const auto* change = std::get_if<ModeRequest>(&request)) {
      const std::lock_guard lock(mutex_);
      mode_ = change->mode;
    }
    return ok_reply({{"request", to_json(request)}});
  }

 private:
  std::mutex mutex_;
  selfsense::runtime::ControlMode mode_{selfsense::runtime::ControlMode::kPosition};
};

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    static_cast<void>(std::fprintf(stderr, "usage: control_test_server SOCKET\n"));
    return 2;
  }
  // Blocked before the server thread starts, so only sigwait() below sees them.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGTERM);
  sigaddset(&stop_signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);
  try {
    EchoHandler handler;
    ControlServerConfig config;
    config.path = argv[1];
    ControlServer server(config, handler);
    server.start();
    static_cast<void>(std::printf("ready\n"));
    static_cast<void>(std::fflush(stdout));
    int signal = 0;
    sigwait(&stop_signals, &signal);
    server.stop();
  } catch (const std::exception& e) {
    static_cast<void>(std::fprintf(stderr, "control_test_server: %s\n", e.what()));
    return 1;
  }
  return 0;
}
