#include "selfsense/daemon/recorder_config.hpp"

#include <cmath>
#include <string>

namespace selfsense::daemon {

namespace {

// The header block of a file (comments and column names) must leave room for rows in the
// first page: see RecordingFile.
constexpr std::size_t kMaxCommentBytes = 2048;
constexpr std::size_t kMaxPrefixChars = 64;
constexpr std::size_t kMinRotateBytes = 4096;
constexpr std::size_t kMaxRingCapacity = std::size_t{1} << 26U;
constexpr double kMaxFlightSeconds = 600.0;
constexpr std::size_t kMaxFlightSamples = std::size_t{1} << 25U;

std::string number(double value) {
  std::string text = std::to_string(value);
  while (text.size() > 1 && text.back() == '0')
    text.pop_back();
  if (!text.empty() && text.back() == '.') text.pop_back();
  return text;
}

bool valid_prefix(const std::string& prefix) {
  if (prefix.empty() || prefix.size() > kMaxPrefixChars || prefix.front() == '.') return false;
  for (const char c : prefix) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '-' || c == '_' || c == '.';
    if (!ok) return false;
  }
  return true;
}

}  // namespace

std::vector<std::string> validate(const RecorderConfig& config) {
  std::vector<std::string> problems;
  const auto add = [&problems](const std::string& key, const std::string& what) {
    problems.push_back("recorder." + key + ": " + what);
  };
  if (config.directory.empty()) add("directory", "must not be empty");
  if (!valid_prefix(config.prefix)) {
    add("prefix", "must be 1 to 64 characters of A-Z a-z 0-9 - _ . not starting with '.', got '" +
                      config.prefix + "'");
  }
  if (config.rotate_bytes < kMinRotateBytes) {
    add("rotate_bytes", "must be >= 4096, got " + std::to_string(config.rotate_bytes));
  }
  if (!(config.flush_period_ms >= 1.0 && config.flush_period_ms <= 60'000.0)) {
    add("flush_period_ms", "must be in [1, 60000], got " + number(config.flush_period_ms));
  }
  if (config.ring_capacity < 2 || config.ring_capacity > kMaxRingCapacity) {
    add("ring_capacity", "must be in [2, 67108864], got " + std::to_string(config.ring_capacity));
  }
  if (!(config.sample_time_s > 0.0 && config.sample_time_s <= 1.0)) {
    add("sample_time_s", "must be in (0, 1], got " + number(config.sample_time_s));
  }
  std::size_t comment_bytes = 0;
  for (std::size_t i = 0; i < config.comments.size(); ++i) {
    const std::string& comment = config.comments[i];
    comment_bytes += comment.size() + 3;
    if (comment.find_first_of("\r\n") != std::string::npos) {
      add("comments[" + std::to_string(i) + "]", "must not hold a line break");
    }
  }
  if (comment_bytes > kMaxCommentBytes) {
    add("comments", "must be at most 2048 bytes in all, got " + std::to_string(comment_bytes));
  }

  const FlightRecorderConfig& flight = config.flight;
  if (!(flight.seconds > 0.0 && flight.seconds <= kMaxFlightSeconds)) {
    add("flight.seconds", "must be in (0, 600], got " + number(flight.seconds));
  } else if (config.sample_time_s > 0.0 &&
             flight.seconds / config.sample_time_s > static_cast<double>(kMaxFlightSamples)) {
    add("flight.seconds", "keeps more than 33554432 samples at this sample time; shorten it");
  }
  if (!(flight.post_trigger_seconds >= 0.0 && flight.post_trigger_seconds < flight.seconds)) {
    add("flight.post_trigger_seconds",
        "must be in [0, flight.seconds), got " + number(flight.post_trigger_seconds));
  }
  if (!valid_prefix(flight.prefix)) {
    add("flight.prefix",
        "must be 1 to 64 characters of A-Z a-z 0-9 - _ . not starting with "
        "'.', got '" +
            flight.prefix + "'");
  }
  return problems;
}

}  // namespace selfsense::daemon
