#include "selfsense/daemon/control_protocol.hpp"

#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

#include "daemon/test_limits.hpp"

namespace selfsense::daemon {
namespace {

using runtime::ControlMode;
using Shape = control::WaveGenerator::Shape;

Request accepted(const std::string& line, const RequestLimits& limits = test::limits()) {
  const ParsedRequest parsed = parse_request(line, limits);
  EXPECT_TRUE(parsed.request.has_value()) << line << " -> " << parsed.error;
  EXPECT_TRUE(parsed.error.empty());
  return parsed.request.value_or(Request{});
}

WaveRequest wave_of(const std::string& line) {
  const Request request = accepted(line);
  EXPECT_TRUE(std::holds_alternative<WaveRequest>(request)) << line;
  return std::holds_alternative<WaveRequest>(request) ? std::get<WaveRequest>(request)
                                                      : WaveRequest{};
}

std::string rejected(const std::string& line, const RequestLimits& limits = test::limits()) {
  const ParsedRequest parsed = parse_request(line, limits);
  EXPECT_FALSE(parsed.request.has_value()) << line;
  EXPECT_FALSE(parsed.error.empty()) << line;
  return parsed.error;
}

TEST(ControlProtocol, RequestsWithoutMembers) {
  EXPECT_TRUE(std::holds_alternative<StatusRequest>(accepted(R"({"request":"status"})")));
  EXPECT_TRUE(std::holds_alternative<ArmRequest>(accepted(R"({"request":"arm"})")));
  EXPECT_TRUE(std::holds_alternative<DisarmRequest>(accepted(R"({"request":"disarm"})")));
  EXPECT_TRUE(std::holds_alternative<ResetRequest>(accepted(R"({"request":"reset"})")));
  EXPECT_TRUE(std::holds_alternative<ReloadRequest>(accepted(R"( { "request" : "reload" } )")));
  EXPECT_EQ(rejected(R"({"request":"arm","force":true})"),
            "arm.force: unknown member (arm takes no members)");
  EXPECT_EQ(rejected(R"({"request":"reload","path":"x.yaml"})"),
            "reload.path: unknown member (reload takes no members)");
}

TEST(ControlProtocol, SetpointInsideTheActiveModesRange) {
  EXPECT_EQ(accepted(R"({"request":"setpoint","value":0.0005})"), Request(SetpointRequest{5e-4}));
  EXPECT_EQ(accepted(R"({"request":"setpoint","value":-1e-4})"), Request(SetpointRequest{-1e-4}));
  EXPECT_EQ(accepted(R"({"request":"setpoint","value":0})"), Request(SetpointRequest{0.0}));
  EXPECT_EQ(rejected(R"({"request":"setpoint","value":0.02})"),
            "setpoint.value: 0.02 is outside [-0.0001, 0.0015] for position");
  EXPECT_EQ(rejected(R"({"request":"setpoint","value":1e308})"),
            "setpoint.value: 1e+308 is outside [-0.0001, 0.0015] for position");
  // The same number is a stress in force mode.
  EXPECT_EQ(accepted(R"({"request":"setpoint","value":-1.5e7})", test::limits(ControlMode::kForce)),
            Request(SetpointRequest{-1.5e7}));
  EXPECT_EQ(rejected(R"({"request":"setpoint","value":0.0005})", test::limits(ControlMode::kForce)),
            "setpoint.value: 0.0005 is outside [-20000000, 0] for force");
  EXPECT_EQ(rejected(R"({"request":"setpoint","value":0})", test::limits(ControlMode::kDamping)),
            "setpoint.value: damping mode takes no setpoint");
}

TEST(ControlProtocol, SetpointMemberErrors) {
  EXPECT_EQ(rejected(R"({"request":"setpoint"})"), "setpoint.value: missing");
  EXPECT_EQ(rejected(R"({"request":"setpoint","value":"0.001"})"),
            "setpoint.value: expected a number, got string");
  EXPECT_EQ(rejected(R"({"request":"setpoint","value":true})"),
            "setpoint.value: expected a number, got boolean");
  EXPECT_EQ(rejected(R"({"request":"setpoint","value":null})"),
            "setpoint.value: expected a number, got null");
  EXPECT_EQ(rejected(R"({"request":"setpoint","value":[0.001]})"),
            "setpoint.value: expected a number, got array");
  EXPECT_EQ(rejected(R"({"request":"setpoint","valeu":0.001})"),
            "setpoint.valeu: unknown member (setpoint takes: value)");
  // JSON has no NaN or Inf, and a number beyond double range is refused by the reader.
  EXPECT_EQ(rejected(R"({"request":"setpoint","value":NaN})").rfind("malformed JSON: ", 0), 0U);
  EXPECT_EQ(rejected(R"({"request":"setpoint","value":1e400})"),
            "malformed JSON: number overflow parsing '1e400'");
}

TEST(ControlProtocol, Modes) {
  EXPECT_EQ(accepted(R"({"request":"mode","name":"position"})"),
            Request(ModeRequest{ControlMode::kPosition}));
  EXPECT_EQ(accepted(R"({"request":"mode","name":"force"})"),
            Request(ModeRequest{ControlMode::kForce}));
  EXPECT_EQ(accepted(R"({"request":"mode","name":"open-loop"})"),
            Request(ModeRequest{ControlMode::kOpenLoop}));
  EXPECT_EQ(accepted(R"({"request":"mode","name":"damping"})"),
            Request(ModeRequest{ControlMode::kDamping}));
  EXPECT_EQ(rejected(R"({"request":"mode","name":"fast"})"),
            R"(mode.name: "fast" is not a mode (position, force, open-loop, damping))");
  EXPECT_EQ(rejected(R"({"request":"mode","name":2})"), "mode.name: expected a string, got number");
  EXPECT_EQ(rejected(R"({"request":"mode"})"), "mode.name: missing");
}

TEST(ControlProtocol, Record) {
  EXPECT_EQ(accepted(R"({"request":"record","action":"start"})"),
            Request(RecordRequest{RecordRequest::Action::kStart}));
  EXPECT_EQ(accepted(R"({"request":"record","action":"stop"})"),
            Request(RecordRequest{RecordRequest::Action::kStop}));
  EXPECT_EQ(rejected(R"({"request":"record","action":"pause"})"),
            R"(record.action: "pause" is not an action (start, stop))");
  EXPECT_EQ(rejected(R"({"request":"record"})"), "record.action: missing");
}

TEST(ControlProtocol, Impulse) {
  EXPECT_EQ(accepted(R"({"request":"impulse","force_n":-300,"duration_s":5e-4})"),
            Request(ImpulseRequest{-300.0, 5e-4}));
  EXPECT_EQ(rejected(R"({"request":"impulse","force_n":2e4,"duration_s":5e-4})"),
            "impulse.force_n: 20000 is outside [-10000, 10000] N");
  // Shorter than a loop period (1e-4 s in the test limits) would never reach the plant.
  EXPECT_EQ(rejected(R"({"request":"impulse","force_n":300,"duration_s":1e-5})"),
            "impulse.duration_s: 1e-05 is outside [0.0001, 1] s (one loop period at least)");
  EXPECT_EQ(rejected(R"({"request":"impulse","force_n":300})"), "impulse.duration_s: missing");
  EXPECT_NE(rejected(R"({"request":"impulse","force_n":300,"duration_s":1e-3,"x":1})").find('x'),
            std::string::npos);
}

TEST(ControlProtocol, State) {
  EXPECT_EQ(accepted(R"({"request":"state","action":"save"})"), Request(StateRequest{}));
  EXPECT_EQ(rejected(R"({"request":"state","action":"load"})"),
            R"(state.action: "load" is not an action (save))");
  EXPECT_EQ(rejected(R"({"request":"state"})"), "state.action: missing");
  EXPECT_EQ(to_json(StateRequest{}).dump(), R"({"action":"save","request":"state"})");
}

TEST(ControlProtocol, Adapt) {
  using A = AdaptRequest::Action;
  EXPECT_EQ(accepted(R"({"request":"adapt","action":"freeze"})"),
            Request(AdaptRequest{A::kFreeze}));
  EXPECT_EQ(accepted(R"({"request":"adapt","action":"resume"})"),
            Request(AdaptRequest{A::kResume}));
  EXPECT_EQ(accepted(R"({"request":"adapt","action":"show"})"), Request(AdaptRequest{A::kShow}));
  EXPECT_EQ(rejected(R"({"request":"adapt","action":"thaw"})"),
            R"(adapt.action: "thaw" is not an action (freeze, resume, show))");
  EXPECT_EQ(rejected(R"({"request":"adapt"})"), "adapt.action: missing");
  EXPECT_EQ(to_json(AdaptRequest{A::kResume}).dump(), R"({"action":"resume","request":"adapt"})");
}

TEST(ControlProtocol, PeriodicWaves) {
  const Request sine = accepted(
      R"({"request":"wave","shape":"sine","amplitude":4e-4,"offset":6e-4,"frequency_hz":1,"phase":0.25,"repeat":3})");
  const auto& wave = std::get<WaveRequest>(sine);
  EXPECT_FALSE(wave.stop);
  EXPECT_EQ(wave.wave.shape, Shape::kSine);
  EXPECT_DOUBLE_EQ(wave.wave.amplitude, 4e-4);
  EXPECT_DOUBLE_EQ(wave.wave.offset, 6e-4);
  EXPECT_DOUBLE_EQ(wave.wave.frequency, 1.0);
  EXPECT_DOUBLE_EQ(wave.wave.phase, 0.25);
  EXPECT_EQ(wave.wave.repeats, 3U);
  // Defaults: offset 0, phase 0, repeat forever.
  const WaveRequest square =
      wave_of(R"({"request":"wave","shape":"square","amplitude":1e-4,"frequency_hz":10})");
  EXPECT_EQ(square.wave.shape, Shape::kSquare);
  EXPECT_EQ(square.wave.offset, 0.0);
  EXPECT_EQ(square.wave.repeats, 0U);
  EXPECT_EQ(wave_of(R"({"request":"wave","shape":"triangle","amplitude":1e-4,"frequency_hz":1000})")
                .wave.shape,
            Shape::kTriangle);
  EXPECT_EQ(
      wave_of(
          R"({"request":"wave","shape":"sine","amplitude":1e-4,"frequency_hz":1,"repeat":18446744073709551615})")
          .wave.repeats,
      18446744073709551615U);
}

TEST(ControlProtocol, PeriodicWaveErrors) {
  const std::string sine = R"({"request":"wave","shape":"sine",)";
  EXPECT_EQ(rejected(sine + R"("frequency_hz":1})"), "wave.amplitude: missing");
  EXPECT_EQ(rejected(sine + R"("amplitude":1e-4})"), "wave.frequency_hz: missing");
  EXPECT_EQ(rejected(sine + R"("amplitude":1e-4,"frequency_hz":0})"),
            "wave.frequency_hz: 0 must be > 0");
  EXPECT_EQ(rejected(sine + R"("amplitude":1e-4,"frequency_hz":1001})"),
            "wave.frequency_hz: 1001 is above the limit 1000");
  EXPECT_EQ(rejected(sine + R"("amplitude":1e-4,"frequency_hz":1,"phase":1})"),
            "wave.phase: 1 is outside [0, 1) cycles");
  EXPECT_EQ(rejected(sine + R"("amplitude":1e-4,"frequency_hz":1,"phase":-0.1})"),
            "wave.phase: -0.1 is outside [0, 1) cycles");
  EXPECT_EQ(rejected(sine + R"("amplitude":1e-4,"frequency_hz":1,"repeat":-1})"),
            "wave.repeat: -1 must be >= 0");
  EXPECT_EQ(rejected(sine + R"("amplitude":1e-4,"frequency_hz":1,"repeat":1.5})"),
            "wave.repeat: expected a whole number >= 0, got 1.5");
  EXPECT_EQ(rejected(sine + R"("amplitude":1e-4,"frequency_hz":1,"repeat":"2"})"),
            "wave.repeat: expected a whole number >= 0, got string");
  EXPECT_EQ(rejected(sine + R"("amplitude":1e-4,"frequency_hz":1,"levels":[1]})"),
            "wave.levels: unknown member (wave shape sine takes: shape, amplitude, offset, "
            "frequency_hz, phase, repeat)");
  EXPECT_EQ(rejected(sine + R"("amplitude":1e-4,"frequency_hz":1,"freq":1})"),
            "wave.freq: unknown member (wave takes: shape, amplitude, offset, frequency_hz, phase, "
            "repeat, levels, dwell_s, values, dt_s)");
  // A name with a control character is echoed escaped, so the error stays one line (found by
  // the fuzzer: "\r" in a member's name).
  EXPECT_EQ(rejected(sine + R"("amplitude":1e-4,"frequency_hz":1,"\requency":1})"),
            "wave.\"\\requency\": unknown member (wave takes: shape, amplitude, offset, "
            "frequency_hz, phase, repeat, levels, dwell_s, values, dt_s)");
}

TEST(ControlProtocol, EveryValueAWaveReachesIsInsideTheRange) {
  const std::string sine = R"({"request":"wave","shape":"sine","frequency_hz":1,)";
  // Range [-1e-4, 1.5e-3]: offset 7e-4 +- 8e-4 just fits, +- 9e-4 does not.
  accepted(sine + R"("amplitude":8e-4,"offset":7e-4})");
  EXPECT_EQ(rejected(sine + R"("amplitude":9e-4,"offset":7e-4})"),
            "wave.amplitude: 0.0009 with offset 0.0007 reaches [-0.0002, 0.0016], outside "
            "[-0.0001, 0.0015] for position");
  // A negative amplitude mirrors the wave; the reach is the same.
  EXPECT_EQ(rejected(sine + R"("amplitude":-9e-4,"offset":7e-4})"),
            "wave.amplitude: -0.0009 with offset 0.0007 reaches [-0.0002, 0.0016], outside "
            "[-0.0001, 0.0015] for position");
  EXPECT_EQ(rejected(sine + R"("amplitude":0,"offset":2e-3})"),
            "wave.offset: 0.002 is outside [-0.0001, 0.0015] for position");
  EXPECT_EQ(rejected(sine + R"("amplitude":1e-4})", test::limits(ControlMode::kDamping)),
            "wave: damping mode takes no setpoint");
  // Staircase and table: their levels and values, scaled, are what is reached.
  EXPECT_EQ(
      rejected(R"({"request":"wave","shape":"staircase","levels":[0,1e-3,2e-3],"dwell_s":0.1})"),
      "wave.amplitude: 1 with offset 0 reaches [0, 0.002], outside [-0.0001, 0.0015] for "
      "position");
  accepted(
      R"({"request":"wave","shape":"staircase","levels":[0,1e-3,2e-3],"dwell_s":0.1,"amplitude":0.5})");
  EXPECT_EQ(rejected(R"({"request":"wave","shape":"table","values":[0,-2e-4],"dt_s":0.1})"),
            "wave.amplitude: 1 with offset 0 reaches [-0.0002, 0], outside [-0.0001, 0.0015] for "
            "position");
}

TEST(ControlProtocol, Staircase) {
  const WaveRequest stairs = wave_of(
      R"({"request":"wave","shape":"staircase","levels":[0,2e-4,4e-4],"dwell_s":0.5,"repeat":2})");
  EXPECT_EQ(stairs.wave.shape, Shape::kStaircase);
  EXPECT_EQ(stairs.wave.levels, (std::vector<double>{0.0, 2e-4, 4e-4}));
  EXPECT_DOUBLE_EQ(stairs.wave.dwell, 0.5);
  EXPECT_EQ(stairs.wave.amplitude, 1.0);
  EXPECT_EQ(stairs.wave.frequency, 0.0);  // the natural period: 3 levels x 0.5 s
  EXPECT_EQ(stairs.wave.repeats, 2U);

  const std::string head = R"({"request":"wave","shape":"staircase",)";
  EXPECT_EQ(rejected(head + R"("dwell_s":0.5})"), "wave.levels: missing");
  EXPECT_EQ(rejected(head + R"("levels":[0],"dwell_s":0})"), "wave.dwell_s: 0 must be > 0");
  EXPECT_EQ(rejected(head + R"("levels":[0],"dwell_s":3601})"),
            "wave.dwell_s: 3601 is above the limit 3600");
  EXPECT_EQ(rejected(head + R"("levels":[],"dwell_s":1})"),
            "wave.levels: 0 values, needs at least 1");
  EXPECT_EQ(rejected(head + R"("levels":[0,"1e-4"],"dwell_s":1})"),
            "wave.levels[1]: expected a number, got string");
  EXPECT_EQ(rejected(head + R"("levels":0.001,"dwell_s":1})"),
            "wave.levels: expected an array of numbers, got number");
  EXPECT_EQ(rejected(head + R"("levels":[0],"dwell_s":1,"frequency_hz":-1})"),
            "wave.frequency_hz: -1 must be >= 0 (0: natural period)");
  EXPECT_EQ(
      rejected(head + R"("levels":[0],"dwell_s":1,"dt_s":1})"),
      "wave.dt_s: unknown member (wave shape staircase takes: shape, levels, dwell_s, amplitude, "
      "offset, frequency_hz, phase, repeat)");
  RequestLimits few = test::limits();
  few.max_levels = 2;
  EXPECT_EQ(rejected(head + R"("levels":[0,0,0],"dwell_s":1})", few),
            "wave.levels: 3 values exceed the limit 2");
  // The generator's own rule: one period of 1e-4 s is a single sample at 10 kHz.
  EXPECT_EQ(rejected(head + R"("levels":[0],"dwell_s":1e-4})"),
            "wave: WaveGenerator.dwell: gives a period of 1 samples, must be >= 2");
}

TEST(ControlProtocol, Table) {
  const WaveRequest table = wave_of(
      R"({"request":"wave","shape":"table","values":[0,1e-4,3e-4],"dt_s":0.01,"offset":1e-4})");
  EXPECT_EQ(table.wave.shape, Shape::kTable);
  EXPECT_EQ(table.wave.table_values, (std::vector<double>{0.0, 1e-4, 3e-4}));
  EXPECT_TRUE(table.wave.table_times.empty());
  EXPECT_DOUBLE_EQ(table.wave.table_dt, 0.01);
  EXPECT_DOUBLE_EQ(table.wave.offset, 1e-4);

  const std::string head = R"({"request":"wave","shape":"table",)";
  EXPECT_EQ(rejected(head + R"("values":[0],"dt_s":0.01})"),
            "wave.values: 1 values, needs at least 2");
  EXPECT_EQ(rejected(head + R"("values":[0,1e-4]})"), "wave.dt_s: missing");
  EXPECT_EQ(rejected(head + R"("values":[0,null],"dt_s":0.01})"),
            "wave.values[1]: expected a number, got null");
  RequestLimits small = test::limits();
  small.max_table_values = 4;
  EXPECT_EQ(rejected(head + R"("values":[0,0,0,0,0],"dt_s":0.01})", small),
            "wave.values: 5 values exceed the limit 4");
}

TEST(ControlProtocol, WaveStopAndShapes) {
  EXPECT_EQ(accepted(R"({"request":"wave","shape":"stop"})"), Request(WaveRequest{true, {}}));
  EXPECT_EQ(rejected(R"({"request":"wave","shape":"stop","amplitude":1})"),
            "wave.amplitude: unknown member (wave shape stop takes: shape)");
  EXPECT_EQ(rejected(R"({"request":"wave"})"), "wave.shape: missing");
  EXPECT_EQ(
      rejected(R"({"request":"wave","shape":"sawtooth"})"),
      R"(wave.shape: "sawtooth" is not a shape (sine, triangle, square, staircase, table, stop))");
  // Stop is allowed whatever the mode.
  accepted(R"({"request":"wave","shape":"stop"})", test::limits(ControlMode::kDamping));
}

TEST(ControlProtocol, RequestMemberErrors) {
  EXPECT_EQ(rejected(R"({"value":1})"),
            "request: missing (one of status, arm, disarm, reset, setpoint, mode, wave, record, "
            "reload, impulse, state, adapt)");
  EXPECT_EQ(rejected(R"({"request":7})"), "request: expected a string, got number");
  EXPECT_EQ(
      rejected(R"({"request":"launch"})"),
      R"(request: "launch" is not a request (status, arm, disarm, reset, setpoint, mode, wave, record, reload, impulse, state, adapt))");
  // A long name is cut in the reply.
  const std::string error = rejected(R"({"request":")" + std::string(10'000, 'x') + R"("})");
  EXPECT_LT(error.size(), 200U);
  EXPECT_NE(error.find("...\" is not a request"), std::string::npos);
}

TEST(ControlProtocol, MalformedLinesAndNonObjects) {
  EXPECT_EQ(rejected(""),
            "malformed JSON: parse error at line 1, column 1: syntax error while parsing value - "
            "unexpected end of input; expected '[', '{', or a literal");
  EXPECT_EQ(rejected("status").rfind("malformed JSON: parse error at line 1, column 1: ", 0), 0U);
  EXPECT_EQ(rejected(R"({"request":"status")").rfind("malformed JSON: ", 0), 0U);
  EXPECT_EQ(rejected(R"({"request":"status"} {"request":"arm"})").rfind("malformed JSON: ", 0), 0U);
  EXPECT_EQ(rejected(R"(["status"])"), "request line: expected a JSON object, got array");
  EXPECT_EQ(rejected("42"), "request line: expected a JSON object, got number");
  EXPECT_EQ(rejected(R"("status")"), "request line: expected a JSON object, got string");
  EXPECT_EQ(rejected("null"), "request line: expected a JSON object, got null");
  EXPECT_EQ(rejected(R"({"request":"status","request":"arm"})"),
            R"(request line: member "request" given twice)");
  EXPECT_EQ(rejected(R"({"request":"setpoint","value":{"si":1}})"),
            "setpoint.value: expected a number, got object");
  EXPECT_EQ(rejected(R"({"request":"setpoint","value":{"si":[1]}})"),
            "request line: nested deeper than an object of arrays of numbers");
  EXPECT_EQ(rejected(R"({"request":"wave","shape":"table","values":[[0],[1]],"dt_s":1})"),
            "request line: nested deeper than an object of arrays of numbers");
  // Deep nesting is refused without building it.
  EXPECT_EQ(rejected(std::string(50'000, '[') + std::string(50'000, ']')),
            "request line: nested deeper than an object of arrays of numbers");
}

// Found by fuzzing (tests/fuzz/corpus/control_request/regression-*): the parser quotes the
// token it stopped in, which was the sender's bytes at any length.
TEST(ControlProtocol, AMalformedLineGivesAShortError) {
  const std::string error = rejected("{" + std::string(1000, '\r') + "\x1b");
  EXPECT_EQ(error.rfind("malformed JSON: parse error at line 1, column 1002: ", 0), 0U) << error;
  EXPECT_LT(error.size(), 300U) << error;
  EXPECT_NE(error.find("<U+000D><U+000D>...'; expected string literal"), std::string::npos)
      << error;
  const std::string word = rejected("[\"" + std::string(500, 'x'));
  EXPECT_LT(word.size(), 300U) << word;
  EXPECT_NE(word.find("last read: '\"" + std::string(63, 'x') + "...'"), std::string::npos) << word;
}

TEST(ControlProtocol, BinaryBytesGiveAnErrorThatStillSerialises) {
  const std::string garbage("\x00\xff\xfe{\"request\":\"st\xc3\x28tus\"}\x01", 25);
  const std::string error = rejected(garbage);
  EXPECT_EQ(error.rfind("malformed JSON: ", 0), 0U);
  const std::string line = reply_line(error_reply(error));
  EXPECT_EQ(line.back(), '\n');
  const auto reply = nlohmann::json::parse(line);
  EXPECT_EQ(reply.at("ok"), false);
}

TEST(ControlProtocol, RandomBytesNeverThrowAndNeverPass) {
  std::mt19937_64 rng(2024);
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_int_distribution<std::size_t> length(0, 200);
  const std::string valid = R"({"request":"setpoint","value":0.0005})";
  int passed = 0;
  for (int i = 0; i < 5000; ++i) {
    std::string line = valid;
    // Mutate a valid request in a few places: most mutations must be refused, none may throw.
    const std::size_t flips = 1 + length(rng) % 4;
    for (std::size_t k = 0; k < flips; ++k) {
      line[length(rng) % line.size()] = static_cast<char>(byte(rng));
    }
    const ParsedRequest parsed = parse_request(line, test::limits());
    EXPECT_NE(parsed.request.has_value(), !parsed.error.empty());
    if (parsed.request) {
      ++passed;
      // Whatever got through is a setpoint inside the range.
      const auto* setpoint = std::get_if<SetpointRequest>(&*parsed.request);
      ASSERT_NE(setpoint, nullptr) << line;
      EXPECT_GE(setpoint->value, -1e-4);
      EXPECT_LE(setpoint->value, 1.5e-3);
    }
    std::string noise(length(rng), '\0');
    for (char& c : noise)
      c = static_cast<char>(byte(rng));
    EXPECT_FALSE(parse_request(noise, test::limits()).request.has_value());
  }
  EXPECT_LT(passed, 1000);
}

TEST(ControlProtocol, EveryRequestRoundTrips) {
  control::WaveGenerator::Config stairs;
  stairs.shape = Shape::kStaircase;
  stairs.levels = {0.0, 2e-4, 4e-4};
  stairs.dwell = 0.25;
  stairs.amplitude = 2.0;
  stairs.offset = 1e-4;
  stairs.frequency = 0.5;
  stairs.repeats = 4;
  control::WaveGenerator::Config table;
  table.shape = Shape::kTable;
  table.table_values = {0.0, 3e-4, 1e-4};
  table.table_dt = 0.125;
  table.phase = 0.5;
  control::WaveGenerator::Config sine;
  sine.amplitude = 1e-4;
  sine.offset = 5e-4;
  sine.frequency = 2.5;
  const std::vector<Request> requests = {StatusRequest{},
                                         ArmRequest{},
                                         DisarmRequest{},
                                         ResetRequest{},
                                         ReloadRequest{},
                                         SetpointRequest{1.25e-4},
                                         ModeRequest{ControlMode::kOpenLoop},
                                         ModeRequest{ControlMode::kDamping},
                                         RecordRequest{RecordRequest::Action::kStop},
                                         ImpulseRequest{250.0, 2e-3},
                                         StateRequest{},
                                         WaveRequest{true, {}},
                                         WaveRequest{false, stairs},
                                         WaveRequest{false, table},
                                         WaveRequest{false, sine}};
  for (const Request& request : requests) {
    const std::string line = to_json(request).dump();
    const ParsedRequest parsed = parse_request(line, test::limits());
    ASSERT_TRUE(parsed.request.has_value()) << line << ": " << parsed.error;
    EXPECT_EQ(*parsed.request, request) << line;
    EXPECT_EQ(to_json(request).at("request"), std::string(request_name(request)));
  }
}

TEST(ControlProtocol, Replies) {
  EXPECT_EQ(reply_line(ok_reply()), "{\"ok\":true}\n");
  EXPECT_EQ(reply_line(ok_reply({{"state", "ready"}})), "{\"ok\":true,\"state\":\"ready\"}\n");
  EXPECT_EQ(reply_line(error_reply("setpoint.value: missing")),
            "{\"error\":\"setpoint.value: missing\",\"ok\":false}\n");
  EXPECT_EQ(mode_name(ControlMode::kOpenLoop), "open-loop");
  EXPECT_EQ(mode_from_name("force"), ControlMode::kForce);
  EXPECT_FALSE(mode_from_name("Force").has_value());
}

TEST(ControlProtocol, LimitsValidation) {
  std::string why;
  EXPECT_TRUE(test::limits().is_valid(&why)) << why;
  RequestLimits bad = test::limits();
  bad.max_frequency_hz = 5000.0;  // not below 0.45 of 10 kHz
  EXPECT_FALSE(bad.is_valid(&why));
  EXPECT_EQ(why, "Violated constraint: RequestLimits.max_frequency_hz in (0, 0.45 / sample_time)");
  bad = test::limits();
  bad.setpoint[1] = SetpointRange{1.0, -1.0};
  EXPECT_FALSE(bad.is_valid(&why));
  EXPECT_EQ(why, "Violated constraint: RequestLimits.setpoint[force]: finite with min <= max");
}

}  // namespace
}  // namespace selfsense::daemon
