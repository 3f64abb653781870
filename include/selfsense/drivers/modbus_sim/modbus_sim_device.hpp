// `selfsense sim-device --modbus-tcp | --modbus-rtu`: the simulated transducer (drivers/sim over
// selfsense::plant) served as a Modbus server with the Modbus driver's default register map,
// the far end of drivers/modbus, paced in real time. Not part of the daemon.
#pragma once

#include <filesystem>
#include <string>
#include <utility>

namespace selfsense::drivers::modbus_sim {

struct ModbusSimDeviceOptions {
  std::filesystem::path plant{"config/plant/daemon.yaml"};
  double rate_hz{1000.0};  // device updates per second; must divide the plant's sample rate
  int unit_id{1};
  int baud{115200};  // RTU
  int priority{0};   // SCHED_FIFO priority of the server; 0: normal scheduling
};

// "HOST:PORT" (the last colon splits; PORT 0 picks a free port, which the server prints).
// Throws std::invalid_argument naming --modbus-tcp otherwise.
[[nodiscard]] std::pair<std::string, int> parse_host_port(const std::string& text);

// Serves until SIGINT or SIGTERM; returns the exit status (0 after a signal).
int serve_modbus_tcp(const ModbusSimDeviceOptions& options, const std::string& host, int port);
int serve_modbus_rtu(const ModbusSimDeviceOptions& options, const std::string& device);

}  // namespace selfsense::drivers::modbus_sim
