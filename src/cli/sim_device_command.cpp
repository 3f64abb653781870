// `selfsense sim-device --modbus-tcp HOST:PORT | --modbus-rtu DEVICE [--plant FILE] [--rate HZ]`
// (contracts.md, "simulated device"): the simulated transducer served over a bus until SIGINT
// or SIGTERM (exit 0). One dispatch per bus; the servers live in sim_device_<bus>.cpp.
#include <CLI/CLI.hpp>
#include <memory>
#include <stdexcept>
#include <string>

#include "commands.hpp"
#include "sim_device.hpp"

namespace selfsense::cli {
namespace {

struct SimDeviceArgs {
  SimDeviceOptions options{};
  std::string modbus_tcp{};
  std::string modbus_rtu{};
};

// "HOST:PORT" (the last colon splits; PORT 0 picks a free port and prints it).
std::pair<std::string, int> host_port(const std::string& s) {
  const std::size_t colon = s.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == s.size()) {
    throw std::invalid_argument("--modbus-tcp: '" + s + "' is not HOST:PORT");
  }
  std::size_t used = 0;
  const int port = std::stoi(s.substr(colon + 1), &used);
  if (used != s.size() - colon - 1 || port < 0 || port > 65535) {
    throw std::invalid_argument("--modbus-tcp: port '" + s.substr(colon + 1) +
                                "' must be within [0, 65535]");
  }
  return {s.substr(0, colon), port};
}

int run(const SimDeviceArgs& a) {
  if (!a.modbus_tcp.empty()) {
    const auto [host, port] = host_port(a.modbus_tcp);
    return serve_modbus_tcp(a.options, host, port);
  }
  return serve_modbus_rtu(a.options, a.modbus_rtu);
}

}  // namespace

void add_sim_device_command(CLI::App& app) {
  auto args = std::make_shared<SimDeviceArgs>();
  CLI::App* cmd = app.add_subcommand(
      "sim-device", "Serve the simulated transducer over a bus, paced in real time");
  auto* tcp = cmd->add_option("--modbus-tcp", args->modbus_tcp,
                              "Modbus TCP server on HOST:PORT (PORT 0: a free port, printed)");
  auto* rtu =
      cmd->add_option("--modbus-rtu", args->modbus_rtu, "Modbus RTU server on a serial DEVICE");
  tcp->excludes(rtu);
  cmd->add_option("--plant", args->options.plant, "Plant configuration (YAML)")
      ->capture_default_str();
  cmd->add_option("--rate", args->options.rate_hz, "Device updates per second")
      ->capture_default_str();
  cmd->add_option("--unit-id", args->options.unit_id, "Modbus unit (slave) address")
      ->capture_default_str()
      ->check(CLI::Range(1, 247));
  cmd->add_option("--baud", args->options.baud, "RTU baud rate")->capture_default_str();
  cmd->add_option("--priority", args->options.priority,
                  "SCHED_FIFO priority (1..99; refused without the right: a warning); 0: normal")
      ->capture_default_str()
      ->check(CLI::Range(0, 99));
  cmd->callback([args, cmd] {
    if (args->modbus_tcp.empty() && args->modbus_rtu.empty()) {
      throw CLI::RequiredError(cmd->get_name() + ": one of --modbus-tcp, --modbus-rtu");
    }
    const int status = run(*args);
    if (status != 0) throw CommandExit{status};
  });
}

}  // namespace selfsense::cli
