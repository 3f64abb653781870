#include "selfsense/drivers/modbus/register_map.hpp"

#include <bit>
#include <cmath>

namespace selfsense::drivers::modbus {

std::string_view to_string(Function f) noexcept {
  return f == Function::kHolding ? "holding" : "input";
}

std::string_view to_string(RegisterType t) noexcept {
  switch (t) {
    case RegisterType::kInt16:
      return "int16";
    case RegisterType::kUint16:
      return "uint16";
    case RegisterType::kInt32:
      return "int32";
    case RegisterType::kFloat32:
      break;
  }
  return "float32";
}

std::string_view to_string(WordOrder w) noexcept {
  return w == WordOrder::kHighFirst ? "high-first" : "low-first";
}

int word_count(RegisterType t) noexcept {
  return (t == RegisterType::kInt16 || t == RegisterType::kUint16) ? 1 : 2;
}

std::string RegisterSpec::problem() const {
  if (address < 0 || address + word_count(type) > 65536) {
    return "address: " + std::to_string(address) + " must be within [0, " +
           std::to_string(65536 - word_count(type)) + "] for a " + std::string(to_string(type));
  }
  if (!std::isfinite(scale) || scale == 0.0) return "scale: must be finite and non-zero";
  if (!std::isfinite(offset)) return "offset: must be finite";
  if (std::isnan(min) || std::isnan(max) || !(min < max)) return "range: min must be < max";
  return {};
}

namespace {

std::uint32_t join(const RegisterSpec& spec, std::span<const std::uint16_t> words) noexcept {
  const std::uint32_t first = words[0];
  const std::uint32_t second = words[1];
  return spec.word_order == WordOrder::kHighFirst ? ((first << 16U) | second)
                                                  : ((second << 16U) | first);
}

void split(const RegisterSpec& spec, std::uint32_t raw, std::span<std::uint16_t> words) noexcept {
  const auto high = static_cast<std::uint16_t>(raw >> 16U);
  const auto low = static_cast<std::uint16_t>(raw & 0xffffU);
  words[0] = spec.word_order == WordOrder::kHighFirst ? high : low;
  words[1] = spec.word_order == WordOrder::kHighFirst ? low : high;
}

// The register's raw value in the spec's unit: the one formula decode() and encode() share.
double scaled(const RegisterSpec& spec, double raw) noexcept {
  return raw * spec.scale + spec.offset;
}

}  // namespace

Decoded decode(const RegisterSpec& spec, std::span<const std::uint16_t> words) noexcept {
  double raw = 0.0;
  switch (spec.type) {
    case RegisterType::kInt16:
      raw = static_cast<double>(std::bit_cast<std::int16_t>(words[0]));
      break;
    case RegisterType::kUint16:
      raw = static_cast<double>(words[0]);
      break;
    case RegisterType::kInt32:
      raw = static_cast<double>(std::bit_cast<std::int32_t>(join(spec, words)));
      break;
    case RegisterType::kFloat32:
      raw = static_cast<double>(std::bit_cast<float>(join(spec, words)));
      break;
  }
  Decoded d;
  d.value = scaled(spec, raw);
  if (!std::isfinite(d.value)) {
    d.status = DecodeStatus::kNotFinite;
  } else if (d.value < spec.min || d.value > spec.max) {
    d.status = DecodeStatus::kOutOfRange;
  }
  return d;
}

bool encode(const RegisterSpec& spec, double value, std::span<std::uint16_t> words) noexcept {
  const double raw = (value - spec.offset) / spec.scale;
  if (!std::isfinite(raw)) return false;
  // The raw value the words will hold; refused where it does not decode to a finite value (an
  // extreme scale and offset overflow on the way back: scale -3e307, offset -1.8e308).
  double held = 0.0;
  switch (spec.type) {
    case RegisterType::kInt16:
      held = std::nearbyint(raw);
      if (held < -32768.0 || held > 32767.0) return false;
      break;
    case RegisterType::kUint16:
      held = std::nearbyint(raw);
      if (held < 0.0 || held > 65535.0) return false;
      break;
    case RegisterType::kInt32:
      held = std::nearbyint(raw);
      if (held < -2147483648.0 || held > 2147483647.0) return false;
      break;
    case RegisterType::kFloat32:
      if (std::abs(raw) > static_cast<double>(std::numeric_limits<float>::max())) return false;
      held = static_cast<double>(static_cast<float>(raw));
      break;
  }
  if (!std::isfinite(scaled(spec, held))) return false;
  switch (spec.type) {
    case RegisterType::kInt16:
      words[0] = std::bit_cast<std::uint16_t>(static_cast<std::int16_t>(held));
      return true;
    case RegisterType::kUint16:
      words[0] = static_cast<std::uint16_t>(held);
      return true;
    case RegisterType::kInt32:
      split(spec, std::bit_cast<std::uint32_t>(static_cast<std::int32_t>(held)), words);
      return true;
    case RegisterType::kFloat32:
      split(spec, std::bit_cast<std::uint32_t>(static_cast<float>(held)), words);
      return true;
  }
  return false;
}

std::string RegisterMap::problem() const {
  struct Named {
    const char* key;
    const RegisterSpec* spec;
  };
  const std::array<Named, 7> all{Named{"e", &e},           Named{"d", &d},
                                 Named{"s_ref", &s_ref},   Named{"t_ref", &t_ref},
                                 Named{"status", &status}, Named{"command", &command},
                                 Named{"temp", &temp}};
  for (const char* required : {"e", "d", "command"}) {
    for (const Named& n : all) {
      if (std::string_view(n.key) == required && !n.spec->enabled) {
        return "registers." + std::string(required) + ": is required";
      }
    }
  }
  for (const Named& n : all) {
    if (!n.spec->enabled) continue;
    const std::string p = n.spec->problem();
    if (!p.empty()) return "registers." + std::string(n.key) + "." + p;
  }
  if (command.function != Function::kHolding) {
    return "registers.command.function: must be holding (input registers are read-only)";
  }
  if (status.enabled && word_count(status.type) != 1) {
    return "registers.status.type: must be int16 or uint16 (the device's status bits)";
  }
  for (std::size_t i = 0; i < all.size(); ++i) {
    for (std::size_t j = i + 1; j < all.size(); ++j) {
      const RegisterSpec& a = *all[i].spec;
      const RegisterSpec& b = *all[j].spec;
      if (!a.enabled || !b.enabled || a.function != b.function) continue;
      const bool apart = a.address + word_count(a.type) <= b.address ||
                         b.address + word_count(b.type) <= a.address;
      if (!apart) {
        return "registers." + std::string(all[j].key) + ".address: " + std::to_string(b.address) +
               " overlaps registers." + all[i].key + " in the " +
               std::string(to_string(a.function)) + " registers";
      }
    }
  }
  return {};
}

RegisterMap default_register_map() {
  const auto input = [](int address) {
    RegisterSpec s;
    s.enabled = true;
    s.address = address;
    s.function = Function::kInput;
    s.type = RegisterType::kFloat32;
    return s;
  };
  RegisterMap m;
  m.e = input(0);
  m.d = input(2);
  m.s_ref = input(4);
  m.t_ref = input(6);
  m.status = input(8);
  m.status.type = RegisterType::kUint16;
  m.command = input(0);
  m.command.function = Function::kHolding;
  return m;
}

RegisterMap served_register_map() {
  RegisterMap m = default_register_map();
  m.temp = m.e;
  m.temp.address = 9;
  return m;
}

}  // namespace selfsense::drivers::modbus
