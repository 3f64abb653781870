#include "selfsense/drivers/can/can_config.hpp"

#include <algorithm>
#include <array>
#include <cstdio>
#include <map>
#include <utility>

namespace selfsense::drivers::can {
namespace {

std::string hex(std::uint32_t id) {
  std::array<char, 16> buf{};
  const int n = std::snprintf(buf.data(), buf.size(), "0x%X", id);
  return std::string(buf.data(), n > 0 ? static_cast<std::size_t>(n) : 0U);
}

// One signal's keys; problems located at driver.signals.NAME.KEY.
SignalConfig read_signal(io::YamlMap m, const std::string& key, std::size_t max_bytes,
                         const io::YamlMap& driver, std::vector<std::string>& problems) {
  SignalConfig out;
  out.present = true;
  const auto problem = [&](const std::string& sub, const std::string& what) {
    problems.push_back(driver.locate(key + (sub.empty() ? "" : "." + sub) + ": " + what));
  };
  const auto id = m.required<std::uint64_t>("id");
  m.read("extended", out.frame.extended);
  out.frame.id = static_cast<std::uint32_t>(std::min<std::uint64_t>(id, 0xFFFFFFFFU));
  std::string why;
  if (id > 0xFFFFFFFFU || !is_valid(out.frame, &why)) {
    problem("id", id > 0xFFFFFFFFU ? "does not fit 29 bits" : why);
  }
  std::string order = "little";
  m.read("byte_order", order);
  if (order == "little") {
    out.signal.order = ByteOrder::kLittle;
  } else if (order == "big") {
    out.signal.order = ByteOrder::kBig;
  } else {
    problem("byte_order", "'" + order + "' is not one of little, big");
  }
  std::uint64_t length = 32;
  m.read("length", length);
  out.signal.length = static_cast<std::uint32_t>(std::min<std::uint64_t>(length, 1000));
  const bool has_byte = m.has("byte");
  const bool has_start = m.has("start_bit");
  if (has_byte == has_start) {
    problem("", "give exactly one of byte (the signal starts at a byte) and start_bit");
  }
  std::uint64_t position = 0;
  if (has_byte) {
    m.read("byte", position);
    // Little endian starts at the byte's bit 0; big endian has its MSB at the byte's bit 7.
    position = out.signal.order == ByteOrder::kLittle ? position * 8U : position * 8U + 7U;
  } else if (has_start) {
    m.read("start_bit", position);
  }
  out.signal.start_bit = static_cast<std::uint32_t>(std::min<std::uint64_t>(position, 100000));
  m.read("signed", out.signal.is_signed);
  m.read("scale", out.signal.scale);
  m.read("offset", out.signal.offset);
  m.finish();
  if (has_byte != has_start && !is_valid(out.signal, max_bytes, &why)) {
    const std::string sub = why.rfind("length", 0) == 0   ? "length"
                            : why.rfind("scale", 0) == 0  ? "scale"
                            : why.rfind("offset", 0) == 0 ? "offset"
                            : has_byte                    ? "byte"
                                                          : "start_bit";
    problem(sub, why + (max_bytes == kClassicMaxBytes ? " (classic CAN; fd: true allows 64)" : ""));
    out.present = false;  // no layout checks on it
  }
  return out;
}

}  // namespace

std::vector<FrameLayout> CanConfig::input_frames() const {
  std::vector<FrameLayout> frames;
  for (const SignalConfig* s : {&e, &d, &s_ref, &t_ref, &temp}) {
    if (!s->present) continue;
    const std::size_t need = bytes_needed(s->signal);
    bool found = false;
    for (FrameLayout& f : frames) {
      if (f.id == s->frame) {
        f.bytes = std::max(f.bytes, need);
        found = true;
      }
    }
    if (!found) frames.push_back({s->frame, need});
  }
  return frames;
}

std::size_t CanConfig::frame_length(std::size_t bytes) const noexcept {
  return fd ? fd_length(bytes) : bytes;
}

void read_can_config(io::YamlMap& driver, double loop_rate_hz, CanConfig& out,
                     std::vector<std::string>& problems) {
  const auto problem = [&](const std::string& key, const std::string& what) {
    problems.push_back(driver.locate("driver." + key + ": " + what));
  };
  out.interface = driver.required<std::string>("interface");
  if (out.interface.empty() || out.interface.size() > 15) {
    problem("interface", "'" + out.interface + "' must be 1 to 15 characters (IFNAMSIZ)");
  }
  driver.read("fd", out.fd);
  driver.read("rx_timeout_ms", out.rx_timeout_ms);
  const double period_ms = loop_rate_hz > 0.0 ? 1000.0 / loop_rate_hz : 0.0;
  if (!(out.rx_timeout_ms >= period_ms && out.rx_timeout_ms <= 10000.0)) {
    problem("rx_timeout_ms", std::to_string(out.rx_timeout_ms) +
                                 " must be within [one loop period (" + std::to_string(period_ms) +
                                 " ms), 10000]");
  }
  std::uint64_t stale = out.stale_cycles;
  driver.read("stale_cycles", stale);
  if (stale > 1000000U) problem("stale_cycles", "must be <= 1000000 (0: off)");
  out.stale_cycles = static_cast<std::uint32_t>(std::min<std::uint64_t>(stale, 1000000U));
  driver.read("error_frames", out.error_frames);
  driver.read("priority", out.priority);
  if (out.priority < 0 || out.priority > 99) {
    problem("priority", std::to_string(out.priority) + " must be 0 (normal) or within [1, 99]");
  }
  driver.read("temp_timeout_ms", out.temp_timeout_ms);
  if (!(out.temp_timeout_ms >= period_ms && out.temp_timeout_ms <= 60000.0)) {
    problem("temp_timeout_ms", std::to_string(out.temp_timeout_ms) +
                                   " must be within [one loop period (" +
                                   std::to_string(period_ms) + " ms), 60000]");
  }

  io::YamlMap signals = driver.map("signals");
  const std::size_t max_bytes = out.max_bytes();
  const auto read = [&](const char* name, bool required, SignalConfig& into) {
    const std::string key = std::string("driver.signals.") + name;
    if (auto m = signals.optional_map(name)) {
      into = read_signal(*m, key, max_bytes, driver, problems);
    } else if (required) {
      problems.push_back(driver.locate(key + ": missing (e, d and command are required)"));
    }
  };
  read("e", true, out.e);
  read("d", true, out.d);
  read("s_ref", false, out.s_ref);
  read("t_ref", false, out.t_ref);
  read("temp", false, out.temp);
  read("command", true, out.command);
  signals.finish();
  if (signals.has("s_ref") != signals.has("t_ref")) {
    problem(signals.has("s_ref") ? "signals.t_ref" : "signals.s_ref",
            "s_ref and t_ref come together (both reference channels or neither)");
  }

  // Layout: no two signals of one frame share a bit; the command has a frame of its own.
  const std::array<std::pair<const char*, const SignalConfig*>, 6> all{{{"e", &out.e},
                                                                        {"d", &out.d},
                                                                        {"s_ref", &out.s_ref},
                                                                        {"t_ref", &out.t_ref},
                                                                        {"temp", &out.temp},
                                                                        {"command", &out.command}}};
  // Per frame, which signal owns each bit.
  std::map<std::pair<std::uint32_t, bool>, std::array<const char*, kFdMaxBytes * 8>> used;
  for (const auto& [name, s] : all) {
    if (!s->present) continue;
    auto [it, inserted] = used.try_emplace({s->frame.id, s->frame.extended});
    if (inserted) it->second.fill(nullptr);
    auto& owners = it->second;
    const char* other = nullptr;
    std::uint32_t at = 0;
    const char* const self = name;
    for_each_bit(s->signal, [&owners, &other, &at, self](std::uint32_t p) {
      if (owners.at(p) != nullptr && other == nullptr) {
        other = owners.at(p);
        at = p;
      }
      owners.at(p) = self;
    });
    if (other != nullptr) {
      problem(std::string("signals.") + name, std::string("overlaps signal ") + other +
                                                  " in frame " + hex(s->frame.id) + " (bit " +
                                                  std::to_string(at) + ")");
    }
  }
  if (out.command.present) {
    for (const auto& [name, s] : all) {
      if (s == &out.command || !s->present || !(s->frame == out.command.frame)) continue;
      problem("signals.command.id", hex(out.command.frame.id) + " is also the frame of input " +
                                        name + " (the command needs a frame of its own)");
      break;
    }
  }
}

}  // namespace selfsense::drivers::can
