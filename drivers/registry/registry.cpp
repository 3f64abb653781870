#include "selfsense/drivers/registry/registry.hpp"

#include <array>
#include <cmath>
#include <exception>
#include <stdexcept>
#include <string_view>

#include "selfsense/drivers/can/can_driver.hpp"
#include "selfsense/drivers/modbus/modbus_driver.hpp"
#include "selfsense/drivers/sim/simulated_transducer.hpp"
#include "selfsense/drivers/spi/spi_driver.hpp"
#include "selfsense/io/yaml_map.hpp"
#include "selfsense/plant_io/plant_yaml.hpp"

namespace selfsense::drivers {

// One row per driver.type: how its section is read and how its driver is built. driver_types()
// (and with it the unknown-type message), read() and create() all follow this table.
struct DriverEntry {
  std::string_view name{};
  void (*read)(io::YamlMap& driver, const daemon::DaemonConfig& config, DriverSections& sections,
               std::vector<std::string>& problems){};
  std::unique_ptr<runtime::Driver> (*create)(const DriverSections& sections){};
};

namespace {

void read_simulated(io::YamlMap& driver, const daemon::DaemonConfig& config,
                    DriverSections& sections, std::vector<std::string>& problems) {
  plant::PlantConfig& plant_config = sections.plant;
  const std::filesystem::path path =
      config.source.parent_path() / driver.required<std::string>("plant");
  TemperatureRamp& ramp = sections.temperature;
  ramp = {};
  if (auto t = driver.optional_map("temperature")) {
    t->read("start_degc", ramp.start_degc);
    ramp.end_degc = ramp.start_degc;
    t->read("end_degc", ramp.end_degc);
    t->read("ramp_s", ramp.ramp_s);
    t->read("swing_degc", ramp.swing_degc);
    t->read("swing_period_s", ramp.swing_period_s);
    t->finish();
    if (!(std::isfinite(ramp.start_degc) && std::isfinite(ramp.end_degc) &&
          std::isfinite(ramp.ramp_s) && ramp.ramp_s >= 0.0)) {
      problems.push_back(driver.locate(
          "driver.temperature: start_degc, end_degc must be finite and ramp_s finite and >= 0"));
    }
    if (!(std::isfinite(ramp.swing_degc) && std::isfinite(ramp.swing_period_s) &&
          ramp.swing_period_s > 0.0)) {
      problems.push_back(driver.locate(
          "driver.temperature: swing_degc must be finite and swing_period_s finite and > 0"));
    }
  }
  try {
    plant_config = plant::load_plant_file(path).plant;
  } catch (const std::exception& e) {
    problems.push_back(driver.locate(std::string("driver.plant: ") + e.what()));
    return;
  }
  if (ramp != TemperatureRamp{} && !plant_config.temperature.enabled) {
    problems.push_back(driver.locate("driver.temperature: the plant (" + path.string() +
                                     ") has no temperature model (plant.temperature.enabled)"));
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

template <modbus::Transport kTransport>
void read_modbus(io::YamlMap& driver, const daemon::DaemonConfig& /*config*/,
                 DriverSections& sections, std::vector<std::string>& problems) {
  modbus::read_modbus_section(driver, kTransport, sections.modbus, problems);
}

std::unique_ptr<runtime::Driver> create_modbus(const DriverSections& sections) {
  return std::make_unique<modbus::ModbusDriver>(sections.modbus);
}

const std::array<DriverEntry, 5> kDrivers{{
    {"simulated",
     [](io::YamlMap& driver, const daemon::DaemonConfig& config, DriverSections& sections,
        std::vector<std::string>& problems) { read_simulated(driver, config, sections, problems); },
     [](const DriverSections& sections) -> std::unique_ptr<runtime::Driver> {
       return std::make_unique<SimulatedTransducer>(sections.plant, sections.temperature);
     }},
    {"can",
     [](io::YamlMap& driver, const daemon::DaemonConfig& config, DriverSections& sections,
        std::vector<std::string>& problems) {
       sections.can = can::CanConfig{};
       can::read_can_config(driver, config.loop.rate_hz, sections.can, problems);
     },
     [](const DriverSections& sections) -> std::unique_ptr<runtime::Driver> {
       return std::make_unique<can::CanDriver>(sections.can);
     }},
    {"modbus-tcp", read_modbus<modbus::Transport::kTcp>, create_modbus},
    {"modbus-rtu", read_modbus<modbus::Transport::kRtu>, create_modbus},
    {"spi",
     [](io::YamlMap& driver, const daemon::DaemonConfig& config, DriverSections& sections,
        std::vector<std::string>& problems) {
       spi::read_spi_config(driver, config.loop.rate_hz, sections.spi, problems);
     },
     [](const DriverSections& sections) -> std::unique_ptr<runtime::Driver> {
       return std::make_unique<spi::SpiDriver>(sections.spi);
     }},
}};

}  // namespace

std::string driver_types() {
  std::string names;
  for (const DriverEntry& entry : kDrivers) {
    if (!names.empty()) names += ", ";
    names += entry.name;
  }
  return names;
}

Registry::Registry() = default;
Registry::~Registry() = default;

void Registry::read(io::YamlMap& driver, const daemon::DaemonConfig& config,
                    std::vector<std::string>& problems) {
  entry_ = nullptr;
  for (const DriverEntry& entry : kDrivers) {
    if (entry.name == config.driver_type) entry_ = &entry;
  }
  if (entry_ == nullptr) {
    problems.push_back(
        driver.locate("driver.type: '" + config.driver_type + "' is not one of " + driver_types()));
    ok_ = false;
    return;
  }
  const std::size_t before = problems.size();
  entry_->read(driver, config, sections_, problems);
  ok_ = problems.size() == before;
}

std::unique_ptr<runtime::Driver> Registry::create() const {
  if (!ok_ || entry_ == nullptr) {
    throw std::logic_error("driver registry: no valid driver section was read");
  }
  return entry_->create(sections_);
}

}  // namespace selfsense::drivers
