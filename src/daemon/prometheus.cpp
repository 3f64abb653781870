#include "selfsense/daemon/prometheus.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <set>

#include "selfsense/base/errno_text.hpp"
#include "selfsense/base/format_number.hpp"

namespace selfsense::daemon {

namespace {

bool is_letter(char c) noexcept {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z');
}
bool is_digit(char c) noexcept {
  return c >= '0' && c <= '9';
}

void append_escaped(std::string& out, std::string_view text, bool quote) {
  for (const char c : text) {
    if (c == '\\') {
      out += "\\\\";
    } else if (c == '\n') {
      out += "\\n";
    } else if (quote && c == '"') {
      out += "\\\"";
    } else {
      out += c;
    }
  }
}

void append_value(std::string& out, double value) {
  if (std::isnan(value)) {
    out += "NaN";
    return;
  }
  if (std::isinf(value)) {
    out += value > 0 ? "+Inf" : "-Inf";
    return;
  }
  constexpr double kExactIntegers = 9007199254740992.0;  // 2^53
  if (value == std::trunc(value) && std::fabs(value) < kExactIntegers) {
    out += std::to_string(static_cast<long long>(value));  // "1000000", not "1e+06"
  } else {
    out += base::format_number(value);
  }
}

[[noreturn]] void fail_errno(const std::string& what) {
  throw std::runtime_error(what + ": " + base::errno_text(errno));
}

}  // namespace

bool valid_metric_name(std::string_view name) noexcept {
  if (name.empty() || is_digit(name.front())) return false;
  for (const char c : name) {
    if (!is_letter(c) && !is_digit(c) && c != '_' && c != ':') return false;
  }
  return true;
}

bool valid_label_name(std::string_view name) noexcept {
  if (name.empty() || is_digit(name.front()) || name.starts_with("__")) return false;
  for (const char c : name) {
    if (!is_letter(c) && !is_digit(c) && c != '_') return false;
  }
  return true;
}

std::string format_exposition(const std::vector<MetricFamily>& families) {
  std::string out;
  std::set<std::string, std::less<>> seen;
  for (const MetricFamily& family : families) {
    if (!valid_metric_name(family.name)) {
      throw MetricError("metric name '" + family.name + "' is not [a-zA-Z_:][a-zA-Z0-9_:]*");
    }
    if (!seen.insert(family.name).second) {
      throw MetricError("metric '" + family.name + "' given twice");
    }
    out += "# HELP ";
    out += family.name;
    out += ' ';
    append_escaped(out, family.help, false);
    out += "\n# TYPE ";
    out += family.name;
    out += family.type == MetricType::kCounter ? " counter\n" : " gauge\n";
    for (const MetricSample& sample : family.samples) {
      out += family.name;
      if (!sample.labels.empty()) {
        out += '{';
        std::set<std::string_view> names;
        for (std::size_t i = 0; i < sample.labels.size(); ++i) {
          const auto& [label, value] = sample.labels[i];
          if (!valid_label_name(label)) {
            throw MetricError("metric '" + family.name + "': label name '" + label +
                              "' is not [a-zA-Z_][a-zA-Z0-9_]* or starts with __");
          }
          if (!names.insert(label).second) {
            throw MetricError("metric '" + family.name + "': label '" + label + "' given twice");
          }
          if (i > 0) out += ',';
          out += label;
          out += "=\"";
          append_escaped(out, value, true);
          out += '"';
        }
        out += '}';
      }
      out += ' ';
      append_value(out, sample.value);
      out += '\n';
    }
  }
  return out;
}

void write_textfile(const std::filesystem::path& path, std::string_view text) {
  const std::filesystem::path dir = path.parent_path().empty() ? "." : path.parent_path();
  std::string temp_name(1, '.');
  temp_name += path.filename().string();
  temp_name += ".tmp";
  const std::filesystem::path temp = dir / temp_name;
  const int fd = ::open(temp.c_str(), O_CREAT | O_TRUNC | O_WRONLY | O_CLOEXEC, 0644);
  if (fd < 0) fail_errno("cannot create " + temp.string());
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int error = n < 0 ? errno : EIO;
      ::close(fd);
      ::unlink(temp.c_str());
      errno = error;
      fail_errno("cannot write " + temp.string());
    }
    done += static_cast<std::size_t>(n);
  }
  // fsync before rename: after a power cut the name never points at an empty file.
  if (::fsync(fd) != 0) {
    const int error = errno;
    ::close(fd);
    ::unlink(temp.c_str());
    errno = error;
    fail_errno("cannot sync " + temp.string());
  }
  ::close(fd);
  if (::rename(temp.c_str(), path.c_str()) != 0) {
    const int error = errno;
    ::unlink(temp.c_str());
    errno = error;
    fail_errno("cannot rename " + temp.string() + " to " + path.string());
  }
}

}  // namespace selfsense::daemon
