#include "selfsense/daemon/csv_row.hpp"

#include <cassert>
#include <charconv>
#include <cmath>
#include <cstring>

namespace selfsense::daemon {

namespace {

// Appends the value (0 when not finite, flagging `bit`) and a separator.
char* put_double(char* out, double value, std::uint32_t bit, std::uint32_t& mask) noexcept {
  if (!std::isfinite(value)) {
    mask |= bit;
    value = 0.0;
  }
  char* const end = std::to_chars(out, out + 32, value).ptr;
  *end = ',';
  return end + 1;
}

template <typename Int>
char* put_int(char* out, Int value, char separator) noexcept {
  char* const end = std::to_chars(out, out + 24, value).ptr;
  *end = separator;
  return end + 1;
}

}  // namespace

std::vector<std::string> RowFormat::column_names() const {
  std::vector<std::string> names{"t", "E", "D", "T_hat", "S_hat", "setpoint", "command", "state"};
  if (references_) {
    names.emplace_back("S");
    names.emplace_back("T");
  }
  if (temperature_) names.emplace_back("temp");
  if (temperature_equivalent_) names.emplace_back("temp_equivalent");
  for (const char* name :
       {"mode", "faults", "estimate_status", "driver_status", "nonfinite", "cycle"}) {
    names.emplace_back(name);
  }
  return names;
}

std::string RowFormat::header_block(const std::vector<std::string>& comments) const {
  std::string text;
  for (const std::string& comment : comments) {
    text += "# ";
    text += comment;
    text += '\n';
  }
  const std::vector<std::string> names = column_names();
  for (std::size_t j = 0; j < names.size(); ++j) {
    text += names[j];
    text += j + 1 == names.size() ? '\n' : ',';
  }
  return text;
}

std::size_t RowFormat::format(const runtime::LoopSample& s, char* out) const noexcept {
  std::uint32_t mask = 0;
  char* p = out;
  p = std::to_chars(p, p + 32, s.t).ptr;  // finite: the recorder checks before it formats
  *p++ = ',';
  p = put_double(p, s.e, nonfinite::kE, mask);
  p = put_double(p, s.d, nonfinite::kD, mask);
  p = put_double(p, s.t_hat, nonfinite::kTHat, mask);
  p = put_double(p, s.s_hat, nonfinite::kSHat, mask);
  p = put_double(p, s.setpoint, nonfinite::kSetpoint, mask);
  p = put_double(p, s.command, nonfinite::kCommand, mask);
  p = put_int(p, static_cast<unsigned>(s.state), ',');
  if (references_) {
    p = put_double(p, s.s_ref, nonfinite::kS, mask);
    p = put_double(p, s.t_ref, nonfinite::kT, mask);
  }
  if (temperature_) p = put_double(p, s.temp_ref, nonfinite::kTemp, mask);
  if (temperature_equivalent_) {
    p = put_double(p, s.temp_equivalent, nonfinite::kTempEquivalent, mask);
  }
  p = put_int(p, static_cast<unsigned>(s.mode), ',');
  p = put_int(p, s.faults, ',');
  p = put_int(p, static_cast<unsigned>(s.estimate_status), ',');
  p = put_int(p, static_cast<unsigned>(s.driver_status), ',');
  p = put_int(p, mask, ',');
  p = put_int(p, s.cycle, '\n');
  const auto length = static_cast<std::size_t>(p - out);
  assert(length <= kMaxRowBytes);
  return length;
}

std::size_t RowFormat::pad(char* row, std::size_t length, std::size_t extra) noexcept {
  assert(length >= 2 && row[length - 1] == '\n');
  if (extra == 0) return length;
  // The last cell starts after the last ','; its digits follow a '-' if it has one. Every
  // reader of numbers (from_chars, strtod, Python, pandas) reads 000123 as 123.
  std::size_t start = length - 1;
  while (start > 0 && row[start - 1] != ',')
    --start;
  if (row[start] == '-') ++start;
  std::memmove(row + start + extra, row + start, length - start);
  std::memset(row + start, '0', extra);
  return length + extra;
}

}  // namespace selfsense::daemon
