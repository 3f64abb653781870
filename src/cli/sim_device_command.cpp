// `selfsense sim-device --can IFACE | --modbus-tcp HOST:PORT | --modbus-rtu DEVICE [...]`
// (docs/drivers/can.md, docs/drivers/modbus.md): the simulated transducer served over a bus, paced
// in real time, until SIGINT or SIGTERM (exit 0) or --duration. This file parses the options, reads
// the files the CAN node needs and dispatches to the chosen bus's server (drivers/can_sim,
// drivers/modbus_sim).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <memory>
#include <stdexcept>
#include <string>

#include "commands.hpp"
#include "selfsense/daemon/config.hpp"
#include "selfsense/drivers/can_sim/can_sim_device.hpp"
#include "selfsense/drivers/modbus_sim/modbus_sim_device.hpp"
#include "selfsense/drivers/registry/registry.hpp"
#include "selfsense/plant_io/plant_yaml.hpp"

namespace selfsense::cli {
namespace {

struct SimDeviceArgs {
  // The bus: exactly one.
  std::string can{};  // --can IFACE
  std::string modbus_tcp{};
  std::string modbus_rtu{};
  // Common; --plant applies to every bus (Modbus defaults to config/plant/daemon.yaml, CAN to
  // the plant's defaults).
  std::filesystem::path plant{};
  double rate_hz{1000.0};
  // Modbus.
  drivers::modbus_sim::ModbusSimDeviceOptions modbus{};
  // CAN.
  std::filesystem::path config{};
  double duration_s{0.0};
  double command_timeout_ms{100.0};
};

// ---- CAN --------------------------------------------------------------------------------------

int fail(const std::string& message) {
  static_cast<void>(std::fprintf(stderr, "sim-device: %s\n", message.c_str()));
  return 1;
}

// The frame layout: the driver section of a daemon configuration with driver.type can.
bool read_layout(const SimDeviceArgs& a, drivers::can::CanConfig& layout, int& status) {
  drivers::Registry registry;
  const daemon::ConfigResult loaded = daemon::load_config(a.config, &registry);
  if (!loaded.ok()) {
    for (const std::string& p : loaded.problems)
      static_cast<void>(std::fprintf(stderr, "%s\n", p.c_str()));
    status = fail(a.config.string() + ": not a valid daemon configuration");
    return false;
  }
  if (loaded.config.driver_type != "can") {
    status = fail(a.config.string() + ": driver.type is '" + loaded.config.driver_type +
                  "', not can (the CAN node takes its frame layout from a can driver section)");
    return false;
  }
  layout = registry.can_config();
  if (!a.can.empty()) layout.interface = a.can;
  return true;
}

int run_can(const SimDeviceArgs& a) {
  if (a.config.empty()) {
    throw std::runtime_error(
        "sim-device --can: --config C.yaml (a daemon configuration with "
        "driver.type can: the frame layout) is required");
  }
  drivers::can_sim::CanSimDeviceOptions c;
  int status = 0;
  if (!read_layout(a, c.layout, status)) return status;
  try {
    if (!a.plant.empty()) c.plant = plant::load_plant_file(a.plant).plant;
  } catch (const std::exception& e) {
    return fail(std::string("--plant: ") + e.what());
  }
  c.rate_hz = a.rate_hz;
  c.duration_s = a.duration_s;
  c.command_timeout_ms = a.command_timeout_ms;
  return drivers::can_sim::run_can_sim_device(c);
}

// ---- Modbus -----------------------------------------------------------------------------------

int run_modbus(const SimDeviceArgs& a) {
  drivers::modbus_sim::ModbusSimDeviceOptions o = a.modbus;
  if (!a.plant.empty()) o.plant = a.plant;
  o.rate_hz = a.rate_hz;
  if (!a.modbus_tcp.empty()) {
    const auto [host, port] = drivers::modbus_sim::parse_host_port(a.modbus_tcp);
    return drivers::modbus_sim::serve_modbus_tcp(o, host, port);
  }
  return drivers::modbus_sim::serve_modbus_rtu(o, a.modbus_rtu);
}

int dispatch(const SimDeviceArgs& a) {
  const int buses = static_cast<int>(!a.can.empty()) + static_cast<int>(!a.modbus_tcp.empty()) +
                    static_cast<int>(!a.modbus_rtu.empty());
  if (buses != 1) {
    throw std::runtime_error(
        "sim-device: give exactly one bus: --can IFACE, --modbus-tcp HOST:PORT or "
        "--modbus-rtu DEVICE");
  }
  if (!a.can.empty()) return run_can(a);
  return run_modbus(a);
}

}  // namespace

void add_sim_device_command(CLI::App& app) {
  auto a = std::make_shared<SimDeviceArgs>();
  CLI::App* cmd = app.add_subcommand(
      "sim-device", "Serve the simulated transducer over a bus, paced in real time");
  // Buses.
  cmd->add_option("--can", a->can, "SocketCAN interface (e.g. vcan0): a CAN node");
  cmd->add_option("--modbus-tcp", a->modbus_tcp,
                  "Modbus TCP server on HOST:PORT (PORT 0: a free port, printed)");
  cmd->add_option("--modbus-rtu", a->modbus_rtu, "Modbus RTU server on a serial DEVICE");
  // Common.
  cmd->add_option("--plant", a->plant,
                  "Plant configuration (YAML); default: config/plant/daemon.yaml for Modbus, "
                  "the plant's defaults for CAN");
  cmd->add_option("--rate", a->rate_hz, "Device updates per second (must divide the plant's rate)")
      ->capture_default_str();
  // CAN.
  cmd->add_option("--config", a->config,
                  "CAN: daemon configuration whose driver section gives the frame layout");
  cmd->add_option("--duration", a->duration_s, "CAN: seconds to run; 0: until SIGINT/SIGTERM")
      ->capture_default_str();
  cmd->add_option("--command-timeout-ms", a->command_timeout_ms,
                  "CAN: no command for this long: the node applies E = 0")
      ->capture_default_str();
  // Modbus.
  cmd->add_option("--unit-id", a->modbus.unit_id, "Modbus unit (slave) address")
      ->capture_default_str()
      ->check(CLI::Range(1, 247));
  cmd->add_option("--baud", a->modbus.baud, "Modbus RTU baud rate")->capture_default_str();
  cmd->add_option("--priority", a->modbus.priority,
                  "Modbus: SCHED_FIFO priority (1..99; refused without the right: a warning); "
                  "0: normal")
      ->capture_default_str()
      ->check(CLI::Range(0, 99));
  cmd->callback([a] {
    const int status = dispatch(*a);
    if (status != 0) throw CommandExit{status};
  });
}

}  // namespace selfsense::cli
