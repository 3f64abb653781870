// Register encoding and decoding (types, word order, scale, offset, range) and the strict
// reading of the Modbus driver section.
#include "selfsense/drivers/modbus/register_map.hpp"

#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "selfsense/drivers/modbus/modbus_config.hpp"
#include "selfsense/io/yaml_map.hpp"

namespace selfsense::drivers::modbus {
namespace {

RegisterSpec spec(RegisterType type, WordOrder order = WordOrder::kHighFirst, double scale = 1.0,
                  double offset = 0.0) {
  RegisterSpec s;
  s.enabled = true;
  s.type = type;
  s.word_order = order;
  s.scale = scale;
  s.offset = offset;
  return s;
}

TEST(RegisterMap, Int16IsTwosComplementWithScaleAndOffset) {
  const RegisterSpec s = spec(RegisterType::kInt16, WordOrder::kHighFirst, 0.5, 10.0);
  std::array<std::uint16_t, 1> w{};
  ASSERT_TRUE(encode(s, 10.0 - 0.5 * 3.0, w));
  EXPECT_EQ(w[0], 0xfffd);  // raw -3
  EXPECT_DOUBLE_EQ(decode(s, w).value, 8.5);
  ASSERT_TRUE(encode(s, 10.0 + 0.5 * 32767, w));
  EXPECT_EQ(w[0], 0x7fff);
  EXPECT_FALSE(encode(s, 10.0 + 0.5 * 32768, w)) << "beyond int16 must be refused, not wrapped";
  EXPECT_FALSE(encode(s, 10.0 - 0.5 * 32769, w));
  w[0] = 0x8000;
  EXPECT_DOUBLE_EQ(decode(s, w).value, 10.0 - 0.5 * 32768);
}

TEST(RegisterMap, Uint16RoundsToNearestAndRefusesNegatives) {
  const RegisterSpec s = spec(RegisterType::kUint16, WordOrder::kHighFirst, 0.01);
  std::array<std::uint16_t, 1> w{};
  ASSERT_TRUE(encode(s, 1.234, w));
  EXPECT_EQ(w[0], 123);
  ASSERT_TRUE(encode(s, 655.35, w));
  EXPECT_EQ(w[0], 65535);
  EXPECT_FALSE(encode(s, -0.01, w));
  EXPECT_NEAR(decode(s, std::array<std::uint16_t, 1>{50000}).value, 500.0, 1e-9);
}

TEST(RegisterMap, Int32WordOrders) {
  const RegisterSpec high = spec(RegisterType::kInt32, WordOrder::kHighFirst);
  const RegisterSpec low = spec(RegisterType::kInt32, WordOrder::kLowFirst);
  std::array<std::uint16_t, 2> w{};
  ASSERT_TRUE(encode(high, 0x12345678, w));
  EXPECT_EQ(w[0], 0x1234);
  EXPECT_EQ(w[1], 0x5678);
  ASSERT_TRUE(encode(low, 0x12345678, w));
  EXPECT_EQ(w[0], 0x5678);
  EXPECT_EQ(w[1], 0x1234);
  ASSERT_TRUE(encode(high, -2, w));
  EXPECT_EQ(w[0], 0xffff);
  EXPECT_EQ(w[1], 0xfffe);
  EXPECT_DOUBLE_EQ(decode(high, w).value, -2.0);
  EXPECT_DOUBLE_EQ(decode(low, w).value, static_cast<double>(std::int32_t{-65537}));
  EXPECT_FALSE(encode(high, 2147483648.0, w));
}

TEST(RegisterMap, Float32BothWordOrdersAsOnTheWire) {
  // 1.0e6f is 0x49742400.
  const RegisterSpec high = spec(RegisterType::kFloat32, WordOrder::kHighFirst);
  const RegisterSpec low = spec(RegisterType::kFloat32, WordOrder::kLowFirst);
  std::array<std::uint16_t, 2> w{};
  ASSERT_TRUE(encode(high, 1.0e6, w));
  EXPECT_EQ(w[0], 0x4974);
  EXPECT_EQ(w[1], 0x2400);
  ASSERT_TRUE(encode(low, 1.0e6, w));
  EXPECT_EQ(w[0], 0x2400);
  EXPECT_EQ(w[1], 0x4974);
  EXPECT_DOUBLE_EQ(decode(low, w).value, 1.0e6);
  EXPECT_DOUBLE_EQ(decode(high, w).value, static_cast<double>(std::bit_cast<float>(0x24004974U)));
}

TEST(RegisterMap, RoundTripsRandomValuesOfEveryType) {
  std::mt19937 rng(12345);
  for (const RegisterType t : {RegisterType::kInt16, RegisterType::kUint16, RegisterType::kInt32,
                               RegisterType::kFloat32}) {
    for (const WordOrder o : {WordOrder::kHighFirst, WordOrder::kLowFirst}) {
      const RegisterSpec s = spec(t, o, 2.5e-3, -1.0);
      const double span = t == RegisterType::kInt16    ? 32000.0
                          : t == RegisterType::kUint16 ? 65000.0
                                                       : 2.0e9;
      std::uniform_real_distribution<double> raw(t == RegisterType::kUint16 ? 0.0 : -span, span);
      for (int i = 0; i < 1000; ++i) {
        const double value = raw(rng) * s.scale + s.offset;
        std::array<std::uint16_t, 2> w{};
        ASSERT_TRUE(encode(s, value, w)) << to_string(t) << " " << value;
        const Decoded d = decode(s, w);
        ASSERT_EQ(d.status, DecodeStatus::kOk);
        const double tolerance =
            t == RegisterType::kFloat32 ? std::abs(value) * 1e-7 + 1e-9 : 0.5 * s.scale + 1e-9;
        ASSERT_NEAR(d.value, value, tolerance) << to_string(t) << " " << to_string(o);
      }
    }
  }
}

TEST(RegisterMap, NanInfinityAndOutOfRangeAreBadDataNotNumbers) {
  RegisterSpec s = spec(RegisterType::kFloat32);
  s.min = -10.0;
  s.max = 10.0;
  EXPECT_EQ(decode(s, std::array<std::uint16_t, 2>{0x7fc0, 0x0000}).status,
            DecodeStatus::kNotFinite);
  EXPECT_EQ(decode(s, std::array<std::uint16_t, 2>{0x7f80, 0x0000}).status,
            DecodeStatus::kNotFinite);
  EXPECT_EQ(decode(s, std::array<std::uint16_t, 2>{0x4130, 0x0000}).status,  // 11.0f
            DecodeStatus::kOutOfRange);
  EXPECT_EQ(decode(s, std::array<std::uint16_t, 2>{0x4120, 0x0000}).status,  // 10.0f
            DecodeStatus::kOk);
  std::array<std::uint16_t, 2> w{1, 2};
  EXPECT_FALSE(encode(s, std::numeric_limits<double>::quiet_NaN(), w));
  EXPECT_FALSE(encode(s, 1e300, w));
  EXPECT_EQ(w[0], 1) << "a refused value leaves the registers untouched";
}

// Found by the fuzz target (a 10 s run of 2026-12-07): with an extreme scale and offset a value
// whose raw count fits the type came back as infinity (the fuzzer's: -6 * -3.2e307 overflows
// before the offset -1.8e308 is added). encode() refuses a value whose registers would not
// decode finite. Here 1.79e308 rounds to the count 1, which decodes to 1.8e308 even exactly.
TEST(RegisterMap, AValueWhoseRegistersWouldNotDecodeFiniteIsRefused) {
  const RegisterSpec s = spec(RegisterType::kInt16, WordOrder::kHighFirst, 1e307, 1.7e308);
  std::array<std::uint16_t, 1> w{7};
  EXPECT_FALSE(encode(s, 1.79e308, w));
  EXPECT_EQ(w[0], 7) << "a refused value leaves the registers untouched";
  // A value whose count decodes finite still encodes, and decodes back.
  ASSERT_TRUE(encode(s, 1.6e308, w));
  EXPECT_EQ(w[0], std::bit_cast<std::uint16_t>(std::int16_t{-1}));
  EXPECT_DOUBLE_EQ(decode(s, w).value, 1.6e308);
}

TEST(RegisterMap, DefaultMapIsValidAndProblemsNameTheEntry) {
  RegisterMap m = default_register_map();
  EXPECT_EQ(m.problem(), "");
  m.status.address = 7;
  EXPECT_EQ(m.problem(),
            "registers.status.address: 7 overlaps registers.t_ref in the input registers");
  m = default_register_map();
  m.command.function = Function::kInput;
  EXPECT_NE(m.problem().find("registers.command.function: must be holding"), std::string::npos);
  m = default_register_map();
  m.d.enabled = false;
  EXPECT_EQ(m.problem(), "registers.d: is required");
  m = default_register_map();
  m.e.scale = 0.0;
  EXPECT_EQ(m.problem(), "registers.e.scale: must be finite and non-zero");
  // The sim-device's map: the default one and the temperature after the status register.
  m = served_register_map();
  EXPECT_EQ(m.problem(), "");
  EXPECT_FALSE(default_register_map().temp.enabled);
  EXPECT_TRUE(m.temp.enabled);
  m.temp.address = 8;
  EXPECT_EQ(m.problem(),
            "registers.temp.address: 8 overlaps registers.status in the input registers");
}

std::vector<std::string> read_section(const std::string& yaml, Transport t,
                                      ModbusConfig* out = nullptr) {
  io::YamlMap root = io::YamlMap::from_string(yaml, "test.yaml");
  io::YamlMap driver = root.map("driver");
  static_cast<void>(driver.required<std::string>("type"));
  std::vector<std::string> problems;
  ModbusConfig c;
  try {
    read_modbus_section(driver, t, c, problems);
    driver.finish();
  } catch (const io::YamlError& e) {
    problems.emplace_back(e.what());
  }
  if (out != nullptr) *out = c;
  return problems;
}

TEST(ModbusConfig, ReadsTcpAndRtuSectionsWithTheirOwnKeys) {
  ModbusConfig c;
  EXPECT_TRUE(read_section("driver:\n  type: modbus-tcp\n  host: plc\n  port: 1502\n"
                           "  registers:\n    e: {address: 10, type: int32, word_order: low-first, "
                           "scale: 0.5}\n    d: {address: 12, type: int16}\n"
                           "    command: {address: 3, function: holding, type: uint16, "
                           "offset: -5}\n    temp: {address: 20, type: int16, scale: 0.1}\n",
                           Transport::kTcp, &c)
                  .empty());
  EXPECT_TRUE(c.registers.temp.enabled);  // the stack's temperature: 0.1 degC per count
  EXPECT_EQ(c.registers.temp.address, 20);
  EXPECT_DOUBLE_EQ(c.registers.temp.scale, 0.1);
  EXPECT_EQ(c.host, "plc");
  EXPECT_EQ(c.port, 1502);
  EXPECT_EQ(c.registers.e.type, RegisterType::kInt32);
  EXPECT_EQ(c.registers.e.word_order, WordOrder::kLowFirst);
  EXPECT_DOUBLE_EQ(c.registers.e.scale, 0.5);
  EXPECT_FALSE(c.registers.s_ref.enabled) << "a given map replaces the default one";
  EXPECT_DOUBLE_EQ(c.registers.command.offset, -5.0);
  EXPECT_TRUE(read_section("driver:\n  type: modbus-rtu\n  device: /dev/ttyS1\n  parity: even\n",
                           Transport::kRtu, &c)
                  .empty());
  EXPECT_EQ(c.parity, 'E');
  EXPECT_TRUE(c.registers.s_ref.enabled) << "no registers: the default map";
  EXPECT_FALSE(c.registers.temp.enabled) << "the default map has no temperature";
}

TEST(ModbusConfig, EveryProblemNamesItsKeyAndLine) {
  const auto p = read_section(
      "driver:\n  type: modbus-tcp\n  host: h\n  port: 0\n  unit_id: 300\n"
      "  response_timeout_s: 0\n  registers:\n    e: {address: 0}\n    d: {address: 1}\n"
      "    command: {address: 0, function: holding}\n",
      Transport::kTcp);
  ASSERT_EQ(p.size(), 4U) << ::testing::PrintToString(p);
  EXPECT_EQ(p[0], "test.yaml:4: driver.port: 0 must be within [1, 65535]");
  EXPECT_EQ(p[1], "test.yaml:5: driver.unit_id: 300 must be within [1, 247]");
  EXPECT_EQ(p[2], "test.yaml:6: driver.response_timeout_s: 0 must be within [0.0001, 10]");
  EXPECT_EQ(
      p[3],
      "test.yaml:9: driver.registers.d.address: 1 overlaps registers.e in the input registers");
  const auto t = read_section(
      "driver:\n  type: modbus-tcp\n  host: h\n  registers:\n    e: {address: 0, type: float64}\n",
      Transport::kTcp);
  ASSERT_EQ(t.size(), 1U);
  EXPECT_NE(t[0].find("test.yaml:5: driver.registers.e.type: 'float64' is not one of"),
            std::string::npos)
      << t[0];
  const auto rtu = read_section("driver:\n  type: modbus-rtu\n  host: h\n", Transport::kRtu);
  ASSERT_EQ(rtu.size(), 1U);
  EXPECT_NE(rtu[0].find("driver.device"), std::string::npos) << rtu[0];
  const auto unknown =
      read_section("driver:\n  type: modbus-tcp\n  host: h\n  baud: 9600\n", Transport::kTcp);
  ASSERT_EQ(unknown.size(), 1U);
  EXPECT_NE(unknown[0].find("driver.baud: unknown key"), std::string::npos) << unknown[0];
}

}  // namespace
}  // namespace selfsense::drivers::modbus
