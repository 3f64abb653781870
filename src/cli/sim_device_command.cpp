// `selfsense sim-device`: the simulated transducer served over a bus (contracts.md, "simulated
// device"), one bus per run. This file only parses the options and dispatches to the server of
// the chosen bus; each bus's server lives in its own file (sim_device_can.cpp, ...).
#include <CLI/CLI.hpp>
#include <memory>
#include <stdexcept>
#include <string>

#include "commands.hpp"
#include "sim_device_can.hpp"

namespace selfsense::cli {
namespace {

struct SimDeviceOptions {
  // The bus: exactly one.
  std::string can{};  // --can IFACE
  // Common to every bus.
  std::filesystem::path config{};
  std::filesystem::path plant{};
  double rate_hz{1000.0};
  double duration_s{0.0};
  double command_timeout_ms{100.0};
};

// ---- per-bus dispatch -------------------------------------------------------------------------

int run_can(const SimDeviceOptions& o) {
  if (o.config.empty()) {
    throw std::runtime_error(
        "sim-device --can: --config C.yaml (a daemon configuration with "
        "driver.type can: the frame layout) is required");
  }
  CanSimDeviceOptions c;
  c.interface = o.can;
  c.config = o.config;
  c.plant = o.plant;
  c.rate_hz = o.rate_hz;
  c.duration_s = o.duration_s;
  c.command_timeout_ms = o.command_timeout_ms;
  return run_can_sim_device(c);
}

int dispatch(const SimDeviceOptions& o) {
  const int buses = o.can.empty() ? 0 : 1;
  if (buses != 1) throw std::runtime_error("sim-device: give exactly one bus: --can IFACE");
  if (!o.can.empty()) return run_can(o);
  return 2;
}

}  // namespace

void add_sim_device_command(CLI::App& app) {
  auto o = std::make_shared<SimDeviceOptions>();
  CLI::App* cmd = app.add_subcommand(
      "sim-device", "Serve the simulated transducer over a bus, paced in real time");
  // Buses.
  cmd->add_option("--can", o->can, "SocketCAN interface (e.g. vcan0): a CAN node");
  // Common.
  cmd->add_option("--config", o->config,
                  "Daemon configuration whose driver section gives the frame layout (CAN)");
  cmd->add_option("--plant", o->plant, "Plant configuration (config/plant/); default: defaults");
  cmd->add_option("--rate", o->rate_hz, "Frames per second (must divide the plant's rate)")
      ->capture_default_str();
  cmd->add_option("--duration", o->duration_s, "Seconds to run; 0: until SIGINT/SIGTERM")
      ->capture_default_str();
  cmd->add_option("--command-timeout-ms", o->command_timeout_ms,
                  "No command for this long: the node applies E = 0")
      ->capture_default_str();
  cmd->callback([o] {
    const int status = dispatch(*o);
    if (status != 0) throw CommandExit{status};
  });
}

}  // namespace selfsense::cli
