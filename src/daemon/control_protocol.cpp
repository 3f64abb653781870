#include "selfsense/daemon/control_protocol.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace selfsense::daemon {
namespace {

using nlohmann::json;
using Shape = control::WaveGenerator::Shape;

constexpr std::array<std::string_view, 12> kRequestNames = {
    "status", "arm",    "disarm", "reset",   "setpoint", "mode",
    "wave",   "record", "reload", "impulse", "state",    "adapt"};
constexpr std::array<std::string_view, 3> kAdaptActions = {"freeze", "resume", "show"};
constexpr std::array<std::string_view, RequestLimits::kModes> kModeNames = {"position", "force",
                                                                            "open-loop", "damping"};
// Echoed user strings are cut so an error reply stays short whatever was sent.
constexpr std::size_t kMaxEcho = 64;
// Members are numbers, strings or arrays of numbers: an object holding arrays is depth 2.
constexpr int kMaxDepth = 2;

// Carries one validation error from deep inside the readers to parse_request().
class Rejected final : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

[[noreturn]] void reject(const std::string& message) {
  throw Rejected(message);
}

// The shortest %g form that reads back as the same double: what the user typed, in the
// form people write it (0.0001 and 1000, not 1e-04 and 1e+03).
std::string number(double value) {
  std::array<char, 32> buffer{};
  if (value == std::trunc(value) && std::abs(value) < 1e15) {
    static_cast<void>(std::snprintf(buffer.data(), buffer.size(), "%.0f", value));
    return buffer.data();
  }
  for (int digits = 1; digits <= 17; ++digits) {
    static_cast<void>(std::snprintf(buffer.data(), buffer.size(), "%.*g", digits, value));
    if (std::strtod(buffer.data(), nullptr) == value) break;
  }
  return buffer.data();
}

// A computed value (a wave's reach), to six digits: rounding noise is not news.
std::string approx(double value) {
  std::array<char, 32> buffer{};
  static_cast<void>(std::snprintf(buffer.data(), buffer.size(), "%.6g", value));
  return buffer.data();
}

std::string echo(std::string_view text) {
  const bool cut = text.size() > kMaxEcho;
  const json echo = std::string(text.substr(0, kMaxEcho)) + (cut ? "..." : "");
  return echo.dump(-1, ' ', false, json::error_handler_t::replace);
}

// A member's name as given where it is plain printable ASCII, else echoed as a JSON string (a
// name with a line break or control character would break the one-line error).
std::string member_name(std::string_view name) {
  const bool plain = name.size() <= kMaxEcho && std::all_of(name.begin(), name.end(), [](char c) {
                       return c >= ' ' && c <= '~';
                     });
  return plain ? std::string(name) : echo(name);
}

std::string joined(std::initializer_list<std::string_view> words) {
  std::string out;
  for (const std::string_view word : words) {
    if (!out.empty()) out += ", ";
    out += word;
  }
  return out;
}

template <std::size_t N>
std::string joined(const std::array<std::string_view, N>& words) {
  std::string out;
  for (const std::string_view word : words) {
    if (!out.empty()) out += ", ";
    out += word;
  }
  return out;
}

std::size_t mode_index(runtime::ControlMode mode) {
  return static_cast<std::size_t>(mode);
}

// Reads the members of one request object. The constructor rejects any member outside
// `allowed` first, so a misspelt member is named as such rather than as a missing one.
class Members final {
 public:
  Members(const json& object, std::string kind, std::initializer_list<std::string_view> allowed,
          const std::string& context)
      : object_(object), kind_(std::move(kind)) {
    for (const auto& [key, value] : object.items()) {
      if (key == "request") continue;
      if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
        const std::string takes = allowed.size() == 0 ? context + " takes no members"
                                                      : context + " takes: " + joined(allowed);
        reject(path(member_name(key)) + ": unknown member (" + takes + ")");
      }
    }
  }

  [[nodiscard]] std::string path(std::string_view member) const {
    return kind_ + "." + std::string(member);
  }
  [[nodiscard]] const json* find(std::string_view member) const {
    const auto it = object_.find(member);
    return it == object_.end() ? nullptr : &*it;
  }
  [[nodiscard]] const json& required(std::string_view member) const {
    const json* value = find(member);
    if (value == nullptr) reject(path(member) + ": missing");
    return *value;
  }

  [[nodiscard]] double number_at(std::string_view member, const json& value) const {
    if (!value.is_number()) reject(path(member) + ": expected a number, got " + value.type_name());
    const double x = value.get<double>();
    if (!std::isfinite(x)) reject(path(member) + ": not a finite number");
    return x;
  }
  [[nodiscard]] double number(std::string_view member) const {
    return number_at(member, required(member));
  }
  [[nodiscard]] double number_or(std::string_view member, double fallback) const {
    const json* value = find(member);
    return value == nullptr ? fallback : number_at(member, *value);
  }
  [[nodiscard]] std::string text(std::string_view member) const {
    const json& value = required(member);
    if (!value.is_string()) reject(path(member) + ": expected a string, got " + value.type_name());
    return value.get<std::string>();
  }
  [[nodiscard]] std::uint64_t count_or(std::string_view member, std::uint64_t fallback) const {
    const json* value = find(member);
    if (value == nullptr) return fallback;
    if (value->is_number_unsigned()) return value->get<std::uint64_t>();
    if (value->is_number_integer()) reject(path(member) + ": " + value->dump() + " must be >= 0");
    reject(path(member) + ": expected a whole number >= 0, got " +
           (value->is_number() ? value->dump() : std::string(value->type_name())));
  }
  [[nodiscard]] std::vector<double> numbers(std::string_view member, std::size_t min_count,
                                            std::size_t max_count) const {
    const json& value = required(member);
    if (!value.is_array())
      reject(path(member) + ": expected an array of numbers, got " + value.type_name());
    if (value.size() < min_count) {
      reject(path(member) + ": " + std::to_string(value.size()) + " values, needs at least " +
             std::to_string(min_count));
    }
    if (value.size() > max_count) {
      reject(path(member) + ": " + std::to_string(value.size()) + " values exceed the limit " +
             std::to_string(max_count));
    }
    std::vector<double> out;
    out.reserve(value.size());
    for (std::size_t i = 0; i < value.size(); ++i) {
      out.push_back(number_at(std::string(member) + "[" + std::to_string(i) + "]", value[i]));
    }
    return out;
  }

 private:
  const json& object_;
  std::string kind_;
};

void check_in(const std::string& path, double value, double min, double max,
              std::string_view unit) {
  if (value < min || value > max) {
    reject(path + ": " + number(value) + " is outside [" + number(min) + ", " + number(max) + "]" +
           std::string(unit));
  }
}

const SetpointRange& active_range(const RequestLimits& limits, const std::string& path) {
  const auto& range = limits.setpoint.at(mode_index(limits.mode));
  if (!range) reject(path + ": " + std::string(mode_name(limits.mode)) + " mode takes no setpoint");
  return *range;
}

SetpointRequest parse_setpoint(const json& object, const RequestLimits& limits) {
  const Members m(object, "setpoint", {"value"}, "setpoint");
  const double value = m.number("value");
  const SetpointRange& range = active_range(limits, m.path("value"));
  check_in(m.path("value"), value, range.min, range.max,
           " for " + std::string(mode_name(limits.mode)));
  return SetpointRequest{value};
}

ModeRequest parse_mode(const json& object) {
  const Members m(object, "mode", {"name"}, "mode");
  const std::string name = m.text("name");
  const auto mode = mode_from_name(name);
  if (!mode)
    reject(m.path("name") + ": " + echo(name) + " is not a mode (" + joined(kModeNames) + ")");
  return ModeRequest{*mode};
}

RecordRequest parse_record(const json& object) {
  const Members m(object, "record", {"action"}, "record");
  const std::string action = m.text("action");
  if (action == "start") return RecordRequest{RecordRequest::Action::kStart};
  if (action == "stop") return RecordRequest{RecordRequest::Action::kStop};
  reject(m.path("action") + ": " + echo(action) + " is not an action (start, stop)");
}

StateRequest parse_state(const json& object) {
  const Members m(object, "state", {"action"}, "state");
  const std::string action = m.text("action");
  if (action == "save") return StateRequest{StateRequest::Action::kSave};
  reject(m.path("action") + ": " + echo(action) + " is not an action (save)");
}

AdaptRequest parse_adapt(const json& object) {
  const Members m(object, "adapt", {"action"}, "adapt");
  const std::string action = m.text("action");
  for (std::size_t i = 0; i < kAdaptActions.size(); ++i) {
    if (action == kAdaptActions[i]) return AdaptRequest{static_cast<AdaptRequest::Action>(i)};
  }
  reject(m.path("action") + ": " + echo(action) + " is not an action (freeze, resume, show)");
}

ImpulseRequest parse_impulse(const json& object, const RequestLimits& limits) {
  const Members m(object, "impulse", {"force_n", "duration_s"}, "impulse");
  const double force = m.number("force_n");
  const double duration = m.number("duration_s");
  check_in(m.path("force_n"), force, -limits.max_impulse_n, limits.max_impulse_n, " N");
  check_in(m.path("duration_s"), duration, limits.sample_time, limits.max_impulse_s,
           " s (one loop period at least)");
  return ImpulseRequest{force, duration};
}

std::optional<Shape> shape_from_name(std::string_view name) {
  if (name == "sine") return Shape::kSine;
  if (name == "triangle") return Shape::kTriangle;
  if (name == "square") return Shape::kSquare;
  if (name == "staircase") return Shape::kStaircase;
  if (name == "table") return Shape::kTable;
  return std::nullopt;
}

std::string_view shape_name(Shape shape) {
  switch (shape) {
    case Shape::kSine:
      return "sine";
    case Shape::kTriangle:
      return "triangle";
    case Shape::kSquare:
      return "square";
    case Shape::kStaircase:
      return "staircase";
    case Shape::kTable:
      return "table";
  }
  return "sine";
}

// The members every playing wave takes; amplitude is required for the periodic shapes, whose
// unit shape has no size of its own.
void read_common(const Members& m, control::WaveGenerator::Config& wave,
                 const RequestLimits& limits) {
  const bool periodic = wave.shape != Shape::kStaircase && wave.shape != Shape::kTable;
  wave.amplitude = periodic ? m.number("amplitude") : m.number_or("amplitude", 1.0);
  wave.offset = m.number_or("offset", 0.0);
  wave.frequency = periodic ? m.number("frequency_hz") : m.number_or("frequency_hz", 0.0);
  if (periodic && wave.frequency <= 0.0) {
    reject(m.path("frequency_hz") + ": " + number(wave.frequency) + " must be > 0");
  }
  if (wave.frequency < 0.0) {
    reject(m.path("frequency_hz") + ": " + number(wave.frequency) +
           " must be >= 0 (0: natural period)");
  }
  if (wave.frequency > limits.max_frequency_hz) {
    reject(m.path("frequency_hz") + ": " + number(wave.frequency) + " is above the limit " +
           number(limits.max_frequency_hz));
  }
  wave.phase = m.number_or("phase", 0.0);
  if (wave.phase < 0.0 || wave.phase >= 1.0) {
    reject(m.path("phase") + ": " + number(wave.phase) + " is outside [0, 1) cycles");
  }
  wave.repeats = m.count_or("repeat", 0);
}

double positive_duration(const Members& m, std::string_view member, const RequestLimits& limits) {
  const double seconds = m.number(member);
  if (seconds <= 0.0) reject(m.path(member) + ": " + number(seconds) + " must be > 0");
  if (seconds > limits.max_dwell_s) {
    reject(m.path(member) + ": " + number(seconds) + " is above the limit " +
           number(limits.max_dwell_s));
  }
  return seconds;
}

// Every value the wave can output lies in offset + amplitude * [lo, hi] of its unit shape.
void check_reach(const Members& m, const control::WaveGenerator::Config& wave,
                 const RequestLimits& limits) {
  const SetpointRange& range = active_range(limits, "wave");
  const std::string mode = " for " + std::string(mode_name(limits.mode));
  check_in(m.path("offset"), wave.offset, range.min, range.max, mode);
  double lo = -1.0;
  double hi = 1.0;
  const std::vector<double>* points = nullptr;
  if (wave.shape == Shape::kStaircase) points = &wave.levels;
  if (wave.shape == Shape::kTable) points = &wave.table_values;
  if (points != nullptr) {
    const auto [min_it, max_it] = std::minmax_element(points->begin(), points->end());
    lo = *min_it;
    hi = *max_it;
  }
  const double a = wave.offset + wave.amplitude * lo;
  const double b = wave.offset + wave.amplitude * hi;
  const double reach_lo = std::min(a, b);
  const double reach_hi = std::max(a, b);
  // A wave that touches a bound up to rounding (offset - amplitude == min) is inside.
  const double slack = 1e-12 * (std::abs(range.min) + std::abs(range.max));
  if (reach_lo < range.min - slack || reach_hi > range.max + slack) {
    reject(m.path("amplitude") + ": " + number(wave.amplitude) + " with offset " +
           number(wave.offset) + " reaches [" + approx(reach_lo) + ", " + approx(reach_hi) +
           "], outside [" + number(range.min) + ", " + number(range.max) + "]" + mode);
  }
}

WaveRequest parse_wave(const json& object, const RequestLimits& limits) {
  const Members shape_only(object, "wave",
                           {"shape", "amplitude", "offset", "frequency_hz", "phase", "repeat",
                            "levels", "dwell_s", "values", "dt_s"},
                           "wave");
  const std::string name = shape_only.text("shape");
  if (name == "stop") {
    const Members m(object, "wave", {"shape"}, "wave shape stop");
    return WaveRequest{true, {}};
  }
  const auto shape = shape_from_name(name);
  if (!shape) {
    reject("wave.shape: " + echo(name) +
           " is not a shape (sine, triangle, square, staircase, table, stop)");
  }
  control::WaveGenerator::Config wave;
  wave.shape = *shape;
  const std::string context = "wave shape " + name;
  if (*shape == Shape::kStaircase) {
    const Members m(
        object, "wave",
        {"shape", "levels", "dwell_s", "amplitude", "offset", "frequency_hz", "phase", "repeat"},
        context);
    wave.levels = m.numbers("levels", 1, limits.max_levels);
    wave.dwell = positive_duration(m, "dwell_s", limits);
    read_common(m, wave, limits);
    check_reach(m, wave, limits);
  } else if (*shape == Shape::kTable) {
    const Members m(
        object, "wave",
        {"shape", "values", "dt_s", "amplitude", "offset", "frequency_hz", "phase", "repeat"},
        context);
    wave.table_values = m.numbers("values", 2, limits.max_table_values);
    wave.table_dt = positive_duration(m, "dt_s", limits);
    read_common(m, wave, limits);
    check_reach(m, wave, limits);
  } else {
    const Members m(object, "wave",
                    {"shape", "amplitude", "offset", "frequency_hz", "phase", "repeat"}, context);
    read_common(m, wave, limits);
    check_reach(m, wave, limits);
  }
  // What is left is the generator's own rule (a period of at least two samples).
  std::string why;
  if (!wave.is_valid(limits.sample_time, &why)) reject("wave: " + why);
  return WaveRequest{false, std::move(wave)};
}

// A request without members of its own.
template <typename Kind>
Kind bare(const json& object, const std::string& kind) {
  const Members m(object, kind, {}, kind);
  return Kind{};
}

Request parse_object(const json& object, const RequestLimits& limits) {
  const auto it = object.find("request");
  if (it == object.end()) reject("request: missing (one of " + joined(kRequestNames) + ")");
  if (!it->is_string()) reject(std::string("request: expected a string, got ") + it->type_name());
  const std::string kind = it->get<std::string>();
  if (kind == "status") return bare<StatusRequest>(object, kind);
  if (kind == "arm") return bare<ArmRequest>(object, kind);
  if (kind == "disarm") return bare<DisarmRequest>(object, kind);
  if (kind == "reset") return bare<ResetRequest>(object, kind);
  if (kind == "reload") return bare<ReloadRequest>(object, kind);
  if (kind == "setpoint") return parse_setpoint(object, limits);
  if (kind == "mode") return parse_mode(object);
  if (kind == "wave") return parse_wave(object, limits);
  if (kind == "record") return parse_record(object);
  if (kind == "impulse") return parse_impulse(object, limits);
  if (kind == "state") return parse_state(object);
  if (kind == "adapt") return parse_adapt(object);
  reject("request: " + echo(kind) + " is not a request (" + joined(kRequestNames) + ")");
}

// The JSON text's own prefix ("[json.exception.parse_error.101] ") says nothing to a user, and
// the token it quotes ("last read: '...'") is the sender's bytes: cut like any echo, at a
// character or "<U+XXXX>" boundary, so the error stays short whatever was sent.
std::string parse_error_text(const char* what) {
  std::string text = what;
  if (!text.empty() && text.front() == '[') {
    const auto end = text.find("] ");
    if (end != std::string::npos) text.erase(0, end + 2);
  }
  constexpr std::string_view kLastRead = "last read: '";
  const auto open = text.find(kLastRead);
  if (open == std::string::npos) return text;
  const std::size_t start = open + kLastRead.size();
  // The token ends before "'; expected ..." when the parser says what it expected.
  auto close = text.rfind("'; expected ");
  if (close == std::string::npos || close < start) close = text.rfind('\'');
  if (close == std::string::npos || close < start || close - start <= kMaxEcho) return text;
  std::size_t cut = start + kMaxEcho;
  const auto escape = text.rfind("<U+", cut);
  if (escape != std::string::npos && escape >= start && text.find('>', escape) >= cut) cut = escape;
  while (cut > start && (static_cast<unsigned char>(text[cut]) & 0xC0U) == 0x80U)
    --cut;
  text.replace(cut, close - cut, "...");
  return text;
}

}  // namespace

bool WaveRequest::operator==(const WaveRequest& other) const {
  if (stop || other.stop) return stop == other.stop;
  const auto& a = wave;
  const auto& b = other.wave;
  return a.shape == b.shape && a.amplitude == b.amplitude && a.offset == b.offset &&
         a.frequency == b.frequency && a.phase == b.phase && a.repeats == b.repeats &&
         a.levels == b.levels && a.dwell == b.dwell && a.table_values == b.table_values &&
         a.table_times == b.table_times && a.table_dt == b.table_dt;
}

bool RequestLimits::is_valid(std::string* why) const {
  const auto fail = [why](std::string message) {
    if (why != nullptr) *why = "Violated constraint: RequestLimits." + std::move(message);
    return false;
  };
  if (!(sample_time > 0.0) || !std::isfinite(sample_time)) return fail("sample_time > 0");
  if (!(max_frequency_hz > 0.0) || !(max_frequency_hz < 0.45 / sample_time)) {
    return fail("max_frequency_hz in (0, 0.45 / sample_time)");
  }
  if (max_levels < 1) return fail("max_levels >= 1");
  if (max_table_values < 2) return fail("max_table_values >= 2");
  if (!(max_dwell_s > 0.0) || !std::isfinite(max_dwell_s)) return fail("max_dwell_s > 0");
  if (!(max_impulse_n > 0.0) || !std::isfinite(max_impulse_n)) return fail("max_impulse_n > 0");
  if (!(max_impulse_s >= sample_time) || !std::isfinite(max_impulse_s)) {
    return fail("max_impulse_s >= sample_time");
  }
  for (std::size_t i = 0; i < kModes; ++i) {
    const auto& range = setpoint.at(i);
    if (range &&
        !(std::isfinite(range->min) && std::isfinite(range->max) && range->min <= range->max)) {
      return fail("setpoint[" + std::string(kModeNames.at(i)) + "]: finite with min <= max");
    }
  }
  return true;
}

ParsedRequest parse_request_json(const nlohmann::json& value, const RequestLimits& limits) {
  if (!value.is_object()) {
    return {std::nullopt,
            std::string("request line: expected a JSON object, got ") + value.type_name()};
  }
  try {
    return {parse_object(value, limits), {}};
  } catch (const Rejected& e) {
    return {std::nullopt, e.what()};
  }
}

ParsedRequest parse_request(std::string_view line, const RequestLimits& limits) {
  // nlohmann keeps the last of duplicated keys silently; an ambiguous request is refused
  // instead. Deeper nesting than any request has is refused before it is built.
  int depth = 0;
  bool too_deep = false;
  std::string duplicate;
  std::vector<std::string> keys;
  const json::parser_callback_t watch = [&](int /*depth*/, json::parse_event_t event,
                                            json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
      case json::parse_event_t::array_start:
        if (++depth > kMaxDepth) too_deep = true;
        return depth <= kMaxDepth;
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        --depth;
        return true;
      case json::parse_event_t::key:
        if (depth == 1 && duplicate.empty()) {
          const auto& key = parsed.get_ref<const std::string&>();
          if (std::find(keys.begin(), keys.end(), key) != keys.end()) duplicate = key;
          keys.push_back(key);
        }
        return true;
      case json::parse_event_t::value:
        return true;
    }
    return true;
  };
  json value;
  try {
    value = json::parse(line.begin(), line.end(), watch);
  } catch (const json::exception& e) {
    return {std::nullopt, "malformed JSON: " + parse_error_text(e.what())};
  }
  if (too_deep) {
    return {std::nullopt, "request line: nested deeper than an object of arrays of numbers"};
  }
  if (!duplicate.empty()) {
    return {std::nullopt, "request line: member " + echo(duplicate) + " given twice"};
  }
  return parse_request_json(value, limits);
}

nlohmann::json to_json(const Request& request) {
  json out = {{"request", std::string(request_name(request))}};
  if (const auto* setpoint = std::get_if<SetpointRequest>(&request)) out["value"] = setpoint->value;
  if (const auto* mode = std::get_if<ModeRequest>(&request))
    out["name"] = std::string(mode_name(mode->mode));
  if (const auto* record = std::get_if<RecordRequest>(&request)) {
    out["action"] = record->action == RecordRequest::Action::kStart ? "start" : "stop";
  }
  if (std::holds_alternative<StateRequest>(request)) out["action"] = "save";
  if (const auto* adapt = std::get_if<AdaptRequest>(&request)) {
    out["action"] = std::string(kAdaptActions[static_cast<std::size_t>(adapt->action)]);
  }
  if (const auto* impulse = std::get_if<ImpulseRequest>(&request)) {
    out["force_n"] = impulse->force_n;
    out["duration_s"] = impulse->duration_s;
  }
  if (const auto* wave_request = std::get_if<WaveRequest>(&request)) {
    if (wave_request->stop) {
      out["shape"] = "stop";
      return out;
    }
    const auto& wave = wave_request->wave;
    out["shape"] = std::string(shape_name(wave.shape));
    out["amplitude"] = wave.amplitude;
    out["offset"] = wave.offset;
    out["frequency_hz"] = wave.frequency;
    out["phase"] = wave.phase;
    out["repeat"] = wave.repeats;
    if (wave.shape == Shape::kStaircase) {
      out["levels"] = wave.levels;
      out["dwell_s"] = wave.dwell;
    }
    if (wave.shape == Shape::kTable) {
      out["values"] = wave.table_values;
      out["dt_s"] = wave.table_dt;
    }
  }
  return out;
}

static_assert(std::variant_size_v<Request> == kRequestNames.size());

std::string_view request_name(const Request& request) {
  return kRequestNames.at(request.index());
}

std::string_view mode_name(runtime::ControlMode mode) {
  return kModeNames.at(mode_index(mode));
}

std::optional<runtime::ControlMode> mode_from_name(std::string_view name) {
  for (std::size_t i = 0; i < kModeNames.size(); ++i) {
    if (kModeNames.at(i) == name) return static_cast<runtime::ControlMode>(i);
  }
  return std::nullopt;
}

nlohmann::json ok_reply() {
  return json{{"ok", true}};
}

nlohmann::json ok_reply(nlohmann::json fields) {
  if (!fields.is_object()) fields = json::object();
  fields["ok"] = true;
  return fields;
}

nlohmann::json error_reply(std::string_view error) {
  return json{{"ok", false}, {"error", std::string(error)}};
}

std::string reply_line(const nlohmann::json& reply) {
  return reply.dump(-1, ' ', false, json::error_handler_t::replace) + "\n";
}

}  // namespace selfsense::daemon
