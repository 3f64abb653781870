#include "selfsense/drivers/modbus/modbus_config.hpp"

#include <cmath>

#include "selfsense/base/format_number.hpp"

namespace selfsense::drivers::modbus {
namespace {

using base::format_number;

}  // namespace

void read_register(io::YamlMap& entry, RegisterSpec& spec) {
  spec = RegisterSpec{};
  spec.enabled = true;
  spec.address = entry.required<int>("address");
  std::string function = "input";
  entry.read("function", function);
  if (function == "input") {
    spec.function = Function::kInput;
  } else if (function == "holding") {
    spec.function = Function::kHolding;
  } else {
    entry.fail("function", "'" + function + "' is not one of input, holding");
  }
  std::string type = "float32";
  entry.read("type", type);
  if (type == "int16") {
    spec.type = RegisterType::kInt16;
  } else if (type == "uint16") {
    spec.type = RegisterType::kUint16;
  } else if (type == "int32") {
    spec.type = RegisterType::kInt32;
  } else if (type == "float32") {
    spec.type = RegisterType::kFloat32;
  } else {
    entry.fail("type", "'" + type + "' is not one of int16, uint16, int32, float32");
  }
  std::string order = "high-first";
  entry.read("word_order", order);
  if (order == "high-first") {
    spec.word_order = WordOrder::kHighFirst;
  } else if (order == "low-first") {
    spec.word_order = WordOrder::kLowFirst;
  } else {
    entry.fail("word_order", "'" + order + "' is not one of high-first, low-first");
  }
  entry.read("scale", spec.scale);
  entry.read("offset", spec.offset);
  std::vector<double> range{spec.min, spec.max};
  entry.read_sequence("range", range);
  if (range.size() != 2) entry.fail("range", "expected [min, max]");
  spec.min = range[0];
  spec.max = range[1];
  entry.finish();
}

void read_registers(io::YamlMap& parent, RegisterMap& map) {
  auto r = parent.optional_map("registers");
  if (!r) return;
  map = RegisterMap{};
  const std::array<std::pair<const char*, RegisterSpec*>, 7> entries{
      std::pair{"e", &map.e},           std::pair{"d", &map.d},
      std::pair{"s_ref", &map.s_ref},   std::pair{"t_ref", &map.t_ref},
      std::pair{"status", &map.status}, std::pair{"command", &map.command},
      std::pair{"temp", &map.temp}};
  for (const auto& [key, spec] : entries) {
    if (auto m = r->optional_map(key)) read_register(*m, *spec);
  }
  r->finish();
}

std::vector<std::string> ModbusConfig::problems() const {
  std::vector<std::string> p;
  const auto check = [&p](bool ok, const std::string& key_and_message) {
    if (!ok) p.push_back(key_and_message);
  };
  if (transport == Transport::kTcp) {
    check(!host.empty(), "host: must not be empty");
    check(port >= 1 && port <= 65535,
          "port: " + std::to_string(port) + " must be within [1, 65535]");
  } else {
    check(!device.empty(), "device: must not be empty");
    check(baud >= 300 && baud <= 4000000,
          "baud: " + std::to_string(baud) + " must be within [300, 4000000]");
    check(data_bits >= 5 && data_bits <= 8,
          "data_bits: " + std::to_string(data_bits) + " must be within [5, 8]");
    check(stop_bits == 1 || stop_bits == 2, "stop_bits: must be 1 or 2");
  }
  check(unit_id >= 1 && unit_id <= 247,
        "unit_id: " + std::to_string(unit_id) + " must be within [1, 247]");
  check(
      response_timeout_s >= 1e-4 && response_timeout_s <= 10.0,
      "response_timeout_s: " + format_number(response_timeout_s) + " must be within [0.0001, 10]");
  check(byte_timeout_s >= 1e-4 && byte_timeout_s <= 10.0,
        "byte_timeout_s: " + format_number(byte_timeout_s) + " must be within [0.0001, 10]");
  check(poll_rate_hz == 0.0 || (poll_rate_hz >= 1.0 && poll_rate_hz <= 100000.0),
        "poll_rate_hz: " + format_number(poll_rate_hz) +
            " must be 0 (the loop's rate) or within [1, 100000]");
  check(priority >= 0 && priority <= 99,
        "priority: " + std::to_string(priority) + " must be 0 (normal) or within [1, 99]");
  check(max_age_s == 0.0 || (max_age_s >= 1e-5 && max_age_s <= sample_timeout_s),
        "max_age_s: " + format_number(max_age_s) +
            " must be 0 (2.5 poll periods) or within [0.00001, sample_timeout_s]");
  check(sample_timeout_s > 0.0 && sample_timeout_s <= 10.0,
        "sample_timeout_s: " + format_number(sample_timeout_s) + " must be within (0, 10]");
  check(reconnect_min_s > 0.0 && reconnect_min_s <= reconnect_max_s && reconnect_max_s <= 60.0,
        "reconnect: min_s and max_s must satisfy 0 < min_s <= max_s <= 60");
  check(reconnect_after_failures >= 1 && reconnect_after_failures <= 1000,
        "reconnect.after_failures: must be within [1, 1000]");
  const std::string map_problem = registers.problem();
  if (!map_problem.empty()) p.push_back(map_problem);
  return p;
}

void read_modbus_section(io::YamlMap& driver, Transport transport, ModbusConfig& out,
                         std::vector<std::string>& problems) {
  out = ModbusConfig{};
  out.transport = transport;
  if (transport == Transport::kTcp) {
    out.host = driver.required<std::string>("host");
    driver.read("port", out.port);
  } else {
    out.device = driver.required<std::string>("device");
    driver.read("baud", out.baud);
    std::string parity = "none";
    driver.read("parity", parity);
    if (parity == "none") {
      out.parity = 'N';
    } else if (parity == "even") {
      out.parity = 'E';
    } else if (parity == "odd") {
      out.parity = 'O';
    } else {
      driver.fail("parity", "'" + parity + "' is not one of none, even, odd");
    }
    driver.read("data_bits", out.data_bits);
    driver.read("stop_bits", out.stop_bits);
  }
  driver.read("unit_id", out.unit_id);
  driver.read("response_timeout_s", out.response_timeout_s);
  driver.read("byte_timeout_s", out.byte_timeout_s);
  driver.read("poll_rate_hz", out.poll_rate_hz);
  driver.read("priority", out.priority);
  driver.read("max_age_s", out.max_age_s);
  driver.read("sample_timeout_s", out.sample_timeout_s);
  if (auto r = driver.optional_map("reconnect")) {
    r->read("min_s", out.reconnect_min_s);
    r->read("max_s", out.reconnect_max_s);
    r->read("after_failures", out.reconnect_after_failures);
    r->finish();
  }
  read_registers(driver, out.registers);
  for (const std::string& p : out.problems())
    problems.push_back(driver.locate("driver." + p));
}

}  // namespace selfsense::drivers::modbus
