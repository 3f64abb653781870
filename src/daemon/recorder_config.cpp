#include "selfsense/daemon/recorder_config.hpp"

#include <string>
#include <utility>
#include <vector>

#include "selfsense/base/check.hpp"

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
  using base::check::violation;
  constexpr const char* kPrefixRule =
      "must be 1 to 64 characters of A-Z a-z 0-9 - _ . not starting with '.'";
  std::vector<std::string> problems;
  const auto add = [&problems](std::string message) { problems.push_back(std::move(message)); };
  if (config.directory.empty()) add("recorder.directory: must not be empty");
  if (!valid_prefix(config.prefix)) {
    add(violation("recorder.prefix", "'" + config.prefix + "'", kPrefixRule));
  }
  if (config.rotate_bytes < kMinRotateBytes) {
    add(violation("recorder.rotate_bytes", config.rotate_bytes, "must be >= 4096"));
  }
  if (!(config.flush_period_ms >= 1.0 && config.flush_period_ms <= 60'000.0)) {
    add(violation("recorder.flush_period_ms", config.flush_period_ms, "must be within [1, 60000]"));
  }
  if (config.ring_capacity < 2 || config.ring_capacity > kMaxRingCapacity) {
    add(violation("recorder.ring_capacity", config.ring_capacity, "must be within [2, 67108864]"));
  }
  if (!(config.sample_time_s > 0.0 && config.sample_time_s <= 1.0)) {
    add(violation("recorder.sample_time_s", config.sample_time_s, "must be within (0, 1]"));
  }
  std::size_t comment_bytes = 0;
  for (std::size_t i = 0; i < config.comments.size(); ++i) {
    const std::string& comment = config.comments[i];
    comment_bytes += comment.size() + 3;
    if (comment.find_first_of("\r\n") != std::string::npos) {
      add("recorder.comments[" + std::to_string(i) + "]: must not hold a line break");
    }
  }
  if (comment_bytes > kMaxCommentBytes) {
    add(violation("recorder.comments", comment_bytes, "bytes in all must be <= 2048"));
  }

  const FlightRecorderConfig& flight = config.flight;
  if (!(flight.seconds > 0.0 && flight.seconds <= kMaxFlightSeconds)) {
    add(violation("recorder.flight.seconds", flight.seconds, "must be within (0, 600]"));
  } else if (config.sample_time_s > 0.0 &&
             flight.seconds / config.sample_time_s > static_cast<double>(kMaxFlightSamples)) {
    add(violation("recorder.flight.seconds", flight.seconds,
                  "keeps more than 33554432 samples at this sample time; shorten it"));
  }
  if (!(flight.post_trigger_seconds >= 0.0 && flight.post_trigger_seconds < flight.seconds)) {
    add(violation("recorder.flight.post_trigger_seconds", flight.post_trigger_seconds,
                  "must be within [0, flight.seconds)"));
  }
  if (!valid_prefix(flight.prefix)) {
    add(violation("recorder.flight.prefix", "'" + flight.prefix + "'", kPrefixRule));
  }
  return problems;
}

}  // namespace selfsense::daemon
