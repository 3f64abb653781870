#include "registry/registry.hpp"

#include <exception>
#include <stdexcept>

#include "can/can_driver.hpp"
#include "modbus/modbus_driver.hpp"
#include "selfsense/io/yaml_map.hpp"
#include "selfsense/plant_io/plant_yaml.hpp"
#include "sim/simulated_transducer.hpp"
#include "spi/spi_driver.hpp"

namespace selfsense::drivers {
namespace {

void read_simulated(io::YamlMap& driver, const daemon::DaemonConfig& config,
                    plant::PlantConfig& plant_config, std::vector<std::string>& problems) {
  const std::filesystem::path path =
      config.source.parent_path() / driver.required<std::string>("plant");
  try {
    plant_config = plant::load_plant_file(path).plant;
  } catch (const std::exception& e) {
    problems.push_back(driver.locate(std::string("driver.plant: ") + e.what()));
    return;
  }
  const double ratio = plant_config.sample_rate_hz / config.loop.rate_hz;
  if (std::abs(ratio - std::round(ratio)) > 1e-9 * ratio || ratio < 1.0) {
    problems.push_back(driver.locate(
        "driver.plant: the plant's sample_rate_hz " + std::to_string(plant_config.sample_rate_hz) +
        " is not a whole multiple of loop.rate_hz " + std::to_string(config.loop.rate_hz) +
        " (the loop rate must divide the ADC rate)"));
  }
  if (plant_config.amplifier.enabled) {
    const double h = plant_config.geometry.layer_thickness_m;
    const double lo = plant_config.amplifier.voltage_min_v / h;
    const double hi = plant_config.amplifier.voltage_max_v / h;
    if (config.control.command_min < lo || config.control.command_max > hi) {
      problems.push_back(driver.locate(
          "control.command_v_per_m: [" + std::to_string(config.control.command_min) + ", " +
          std::to_string(config.control.command_max) + "] must lie inside the amplifier's range [" +
          std::to_string(lo) + ", " + std::to_string(hi) + "] V/m"));
    }
  }
}

}  // namespace

std::string driver_types() {
  return "simulated, can, modbus-tcp, modbus-rtu, spi";
}

void Registry::read(io::YamlMap& driver, const daemon::DaemonConfig& config,
                    std::vector<std::string>& problems) {
  type_ = config.driver_type;
  const std::size_t before = problems.size();
  if (type_ == "simulated") {
    read_simulated(driver, config, plant_, problems);
  } else if (type_ == "can") {
    can_ = can::CanConfig{};
    can::read_can_config(driver, config.loop.rate_hz, can_, problems);
  } else if (type_ == "modbus-tcp" || type_ == "modbus-rtu") {
    modbus::read_modbus_section(
        driver, type_ == "modbus-tcp" ? modbus::Transport::kTcp : modbus::Transport::kRtu, modbus_,
        problems);
  } else if (type_ == "spi") {
    spi::read_spi_config(driver, config.loop.rate_hz, spi_, problems);
  } else {
    problems.push_back(
        driver.locate("driver.type: '" + type_ + "' is not one of " + driver_types()));
  }
  ok_ = problems.size() == before;
}

std::unique_ptr<runtime::Driver> Registry::create() const {
  if (!ok_) throw std::logic_error("driver registry: no valid driver section was read");
  if (type_ == "can") return std::make_unique<can::CanDriver>(can_);
  if (type_ == "spi") return std::make_unique<spi::SpiDriver>(spi_);
  if (type_ == "modbus-tcp" || type_ == "modbus-rtu") {
    return std::make_unique<modbus::ModbusDriver>(modbus_);
  }
  return std::make_unique<SimulatedTransducer>(plant_);
}

}  // namespace selfsense::drivers
