// The driver section of a daemon configuration for the Modbus driver (docs/drivers/modbus.md),
// read strictly: unknown keys are errors, every problem names its key.
//
//   type: modbus-tcp | modbus-rtu
//   host: 127.0.0.1    port: 502                              (modbus-tcp)
//   device: /dev/ttyUSB0  baud: 115200  parity: none|even|odd  data_bits: 8  stop_bits: 1
//                                                             (modbus-rtu)
//   unit_id: 1                 the device's unit (slave) address, 1..247
//   response_timeout_s: 0.02   byte_timeout_s: 0.005
//   poll_rate_hz: 0            bus polls per second; 0: the loop's rate
//   priority: 0                the bus thread's SCHED_FIFO priority (1..99); 0: normal
//   max_age_s: 0               the held sample older than this: kStale; 0: 2.5 poll periods
//   sample_timeout_s: 0.02     a sample older than this: kTimeout
//   reconnect: {min_s: 0.01, max_s: 1.0, after_failures: 3}
//   registers: {e: {...}, d: {...}, s_ref, t_ref, status, command, temp}  (absent: the default
//              map; temp: the stack's temperature [degC], the driver's has_temperature())
//     each: {address: N, function: input|holding, type: int16|uint16|int32|float32,
//            word_order: high-first|low-first, scale: 1, offset: 0, range: [min, max]}
// Not real-time code.
#pragma once

#include <string>
#include <vector>

#include "selfsense/drivers/modbus/register_map.hpp"
#include "selfsense/io/yaml_map.hpp"

namespace selfsense::drivers::modbus {

enum class Transport : std::uint8_t { kTcp = 0, kRtu };

struct ModbusConfig {
  Transport transport{Transport::kTcp};
  std::string host{"127.0.0.1"};
  int port{502};
  std::string device{};
  int baud{115200};
  char parity{'N'};  // 'N', 'E', 'O'
  int data_bits{8};
  int stop_bits{1};
  int unit_id{1};
  double response_timeout_s{0.02};
  double byte_timeout_s{0.005};
  double poll_rate_hz{0.0};  // 0: the loop's rate
  int priority{0};           // bus thread SCHED_FIFO priority; 0: normal scheduling
  double max_age_s{0.0};     // 0: 2.5 poll periods (two polls missed)
  double sample_timeout_s{0.02};
  double reconnect_min_s{0.01};
  double reconnect_max_s{1.0};
  int reconnect_after_failures{3};
  RegisterMap registers{default_register_map()};

  // Empty when valid, otherwise "KEY: what" (keys relative to the driver section).
  [[nodiscard]] std::vector<std::string> problems() const;
};

// Reads the keys of one register entry ("registers.e") into spec (enabled).
void read_register(io::YamlMap& entry, RegisterSpec& spec);
// Reads `registers` (all entries replace the default map) when present.
void read_registers(io::YamlMap& parent, RegisterMap& map);

// Reads a driver section whose type (modbus-tcp or modbus-rtu) was taken; problems are appended
// located ("FILE:LINE: driver.KEY: what"). Throws io::YamlError on a malformed value.
void read_modbus_section(io::YamlMap& driver, Transport transport, ModbusConfig& out,
                         std::vector<std::string>& problems);

}  // namespace selfsense::drivers::modbus
