// The table of drivers the daemon can build, chosen by `driver.type` in its configuration at
// run time (no rebuild, no preprocessor selection). Reads each driver's own keys (strictly,
// problems named with file, line and key) and builds the driver. Not real-time code. The types
// are one table in registry.cpp (name, section reader, factory): a new driver is a row there.
//
//   type: simulated     the simulated transducer (drivers/sim)
//     plant: PATH       a plant configuration (config/plant/), relative to the daemon's file
//   type: can           SocketCAN (drivers/can, docs/drivers/can.md)
//     interface, fd, rx_timeout_ms, stale_cycles, error_frames, signals: {e, d, s_ref, t_ref,
//     command}          see include/selfsense/drivers/can/can_config.hpp
//   type: modbus-tcp | modbus-rtu   the Modbus driver (drivers/modbus, docs/drivers/modbus.md)
//   type: spi           ADS131M04 ADC + DAC8563 DAC on spidev, GPIO on libgpiod (drivers/spi,
//                       docs/drivers/spi.md; keys in include/selfsense/drivers/spi/spi_config.hpp)
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "selfsense/daemon/config.hpp"
#include "selfsense/drivers/can/can_config.hpp"
#include "selfsense/drivers/modbus/modbus_config.hpp"
#include "selfsense/drivers/sim/simulated_transducer.hpp"
#include "selfsense/drivers/spi/spi_config.hpp"
#include "selfsense/plant/config.hpp"
#include "selfsense/runtime/driver.hpp"

namespace selfsense::drivers {

// Every driver type, for messages: "simulated, can, modbus-tcp, modbus-rtu, spi" (the names of
// the table in registry.cpp, in its order).
[[nodiscard]] std::string driver_types();

// What the driver sections are read into; only the chosen type's member is filled.
struct DriverSections {
  plant::PlantConfig plant{};
  TemperatureRamp temperature{};  // the simulated stack's (simulated_transducer.hpp)
  can::CanConfig can{};
  modbus::ModbusConfig modbus{};
  spi::SpiConfig spi{};
};

// A row of the driver table (registry.cpp): a type's name, how its section is read, how its
// driver is built.
struct DriverEntry;

class Registry final : public daemon::DriverSectionReader {
 public:
  // Out of line: GCC 12 at -O3 takes the inline ones for reads of uninitialised vectors.
  Registry();
  Registry(const Registry&) = delete;
  Registry& operator=(const Registry&) = delete;
  Registry(Registry&&) = delete;
  Registry& operator=(Registry&&) = delete;
  ~Registry() override;
  void read(io::YamlMap& driver, const daemon::DaemonConfig& config,
            std::vector<std::string>& problems) override;
  // The driver read last; throws std::logic_error if read() found problems or was not called.
  [[nodiscard]] std::unique_ptr<runtime::Driver> create() const;
  // The CAN section read last (driver.type can), for `selfsense sim-device --can`.
  [[nodiscard]] const can::CanConfig& can_config() const noexcept { return sections_.can; }
  // The SPI section read last (driver.type spi), for tests and benches that build the driver
  // on emulated hardware.
  [[nodiscard]] const spi::SpiConfig& spi_config() const noexcept { return sections_.spi; }

 private:
  const DriverEntry* entry_{nullptr};
  bool ok_{false};
  DriverSections sections_{};
};

}  // namespace selfsense::drivers
