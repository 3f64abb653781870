// Fuzz target: control-socket request lines (daemon/control_protocol.hpp). The first byte picks
// the active mode (its low two bits), the rest is the line.
// Properties:
//  - parse_request never throws and gives exactly one of a request or an error;
//  - an error is one line of at most kMaxError characters, and it starts with where the problem
//    is: "malformed JSON: " with the column (or the number that overflowed), "request line: ", or
//    the request member's path
//    ("request: ", "setpoint.value: ", "wave.levels[3]: ", ...);
//  - an accepted request written back (to_json, as `selfsense ctl` sends it) parses to an equal
//    request, and request_name() is its "request" member.
#include <array>
#include <cstdint>
#include <exception>
#include <string>
#include <string_view>
#include <variant>

#include "fuzz_check.hpp"
#include "selfsense/daemon/control_protocol.hpp"

namespace {

using selfsense::daemon::RequestLimits;
using selfsense::fuzz::require;

// Echoed input is cut to 64 characters; the longest fixed text (the list of requests or
// members) is far below the rest.
constexpr std::size_t kMaxError = 400;

constexpr std::array<std::string_view, 10> kLocations = {
    "request:", "status", "arm", "disarm", "reset", "reload", "setpoint", "mode", "wave", "record"};

RequestLimits limits_for(std::uint8_t selector) {
  RequestLimits limits;
  limits.mode = static_cast<selfsense::runtime::ControlMode>(selector & 3U);
  limits.setpoint[0] = selfsense::daemon::SetpointRange{-5e-4, 1.5e-3};  // position
  limits.setpoint[1] = selfsense::daemon::SetpointRange{-1.5e7, 5e6};    // force
  limits.setpoint[2] = selfsense::daemon::SetpointRange{-5e-4, 1.5e-3};  // open-loop
  return limits;
}

bool located(const std::string& error) {
  if (error.starts_with("malformed JSON: ")) {
    // The parser's position, or the number that overflowed (it names itself).
    return error.find("column ") != std::string::npos ||
           error.starts_with("malformed JSON: number overflow parsing '");
  }
  if (error.starts_with("request line: ")) return true;
  for (const std::string_view where : kLocations) {
    if (!error.starts_with(where)) continue;
    if (where.ends_with(':')) return true;
    const char next = error.size() > where.size() ? error[where.size()] : '\0';
    if (next == ':' || next == '.') return true;
  }
  return false;
}

}  // namespace

// NOLINTNEXTLINE(readability-identifier-naming): the name libFuzzer calls.
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const RequestLimits limits = limits_for(data[0]);
  const std::string line = selfsense::fuzz::as_text(data + 1, size - 1);

  selfsense::daemon::ParsedRequest parsed;
  try {
    parsed = selfsense::daemon::parse_request(line, limits);
  } catch (const std::exception& e) {
    selfsense::fuzz::violated("parse_request never throws", e.what());
  }
  require(parsed.request.has_value() != !parsed.error.empty(),
          "either a request or an error, never both or none", parsed.error);
  if (!parsed.request) {
    require(parsed.error.find_first_of("\r\n") == std::string::npos, "an error is one line",
            parsed.error);
    require(parsed.error.size() <= kMaxError, "an error is short", parsed.error);
    require(located(parsed.error), "an error names where the problem is", parsed.error);
    return 0;
  }
  const nlohmann::json written = selfsense::daemon::to_json(*parsed.request);
  require(
      written.value("request", std::string{}) == selfsense::daemon::request_name(*parsed.request),
      "request_name() is the written request member", written.dump());
  const std::string again = written.dump();
  const selfsense::daemon::ParsedRequest reparsed = selfsense::daemon::parse_request(again, limits);
  require(reparsed.request.has_value(), "a written request parses again",
          again + " -> " + reparsed.error);
  require(*reparsed.request == *parsed.request, "a written request parses to an equal request",
          line + " -> " + again);
  return 0;
}
