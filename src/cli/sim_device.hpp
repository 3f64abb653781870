// `selfsense sim-device`: the simulated transducer (drivers/sim over selfsense::plant) served
// over a field bus, paced in real time. The option parsing is in sim_device_command.cpp; each
// bus has its own server file (sim_device_modbus.cpp).
#pragma once

#include <filesystem>
#include <string>

namespace selfsense::cli {

struct SimDeviceOptions {
  std::filesystem::path plant{"config/plant/daemon.yaml"};
  double rate_hz{1000.0};  // device updates per second; must divide the plant's sample rate
  int unit_id{1};
  int baud{115200};  // RTU
  int priority{0};   // SCHED_FIFO priority of the server; 0: normal scheduling
};

// Serves until SIGINT or SIGTERM; returns the exit status (0 after a signal).
int serve_modbus_tcp(const SimDeviceOptions& options, const std::string& host, int port);
int serve_modbus_rtu(const SimDeviceOptions& options, const std::string& device);

}  // namespace selfsense::cli
