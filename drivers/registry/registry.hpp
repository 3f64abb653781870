// The table of drivers the daemon can build, chosen by `driver.type` in its configuration at
// run time (no rebuild, no preprocessor selection). Reads each driver's own keys (strictly,
// problems named with file, line and key) and builds the driver. Not real-time code.
//
//   type: simulated     the simulated transducer (drivers/sim)
//     plant: PATH       a plant configuration (config/plant/), relative to the daemon's file
//   type: can           SocketCAN (drivers/can, docs/drivers/can.md)
//     interface, fd, rx_timeout_ms, stale_cycles, error_frames, signals: {e, d, s_ref, t_ref,
//     command}          see drivers/can/can_config.hpp
//   type: modbus-tcp | modbus-rtu   the Modbus driver (drivers/modbus, docs/drivers/modbus.md)
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "can/can_config.hpp"
#include "modbus/modbus_config.hpp"
#include "selfsense/daemon/config.hpp"
#include "selfsense/plant/config.hpp"
#include "selfsense/runtime/driver.hpp"

namespace selfsense::drivers {

// Every driver type, for messages: "simulated, can, modbus-tcp, modbus-rtu".
[[nodiscard]] std::string driver_types();

class Registry final : public daemon::DriverSectionReader {
 public:
  void read(io::YamlMap& driver, const daemon::DaemonConfig& config,
            std::vector<std::string>& problems) override;
  // The driver read last; throws std::logic_error if read() found problems or was not called.
  [[nodiscard]] std::unique_ptr<runtime::Driver> create() const;
  // The CAN section read last (driver.type can), for `selfsense sim-device --can`.
  [[nodiscard]] const can::CanConfig& can_config() const noexcept { return can_; }

 private:
  std::string type_{};
  bool ok_{false};
  plant::PlantConfig plant_{};
  can::CanConfig can_{};
  modbus::ModbusConfig modbus_{};
};

}  // namespace selfsense::drivers
