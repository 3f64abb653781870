// `selfsense sim-device --can IFACE`: the simulated transducer served as a CAN node
// (contracts.md, "simulated device"). Not part of the daemon.
#pragma once

#include <filesystem>
#include <string>

namespace selfsense::cli {

struct CanSimDeviceOptions {
  std::string interface {};          // SocketCAN interface (overrides driver.interface)
  std::filesystem::path config{};    // a daemon configuration with driver.type can: the layout
  std::filesystem::path plant{};     // plant configuration (config/plant/); empty: defaults
  double rate_hz{1000.0};            // input frames per second, paced in real time
  double duration_s{0.0};            // 0: until SIGINT or SIGTERM
  double command_timeout_ms{100.0};  // no command for this long: the node applies E = 0
};

// Runs until SIGINT/SIGTERM (or the duration); prints one summary line on stdout. Returns the
// process exit status: 0 after a clean stop, 1 on a setup error (printed on stderr).
int run_can_sim_device(const CanSimDeviceOptions& options);

}  // namespace selfsense::cli
