// Wall-clock stamps for file names and header comments (UTC, so that files from boards in
// different time zones sort together). Private to the daemon library.
#pragma once

#include <time.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <string>

namespace selfsense::daemon::detail {

// compact: 20261123T111938Z (file names); otherwise 2026-11-23T11:19:38.123Z (comments).
inline std::string utc_stamp(std::chrono::system_clock::time_point when, bool compact) {
  const auto since_epoch = when.time_since_epoch();
  const auto seconds = std::chrono::duration_cast<std::chrono::seconds>(since_epoch);
  const auto millis =
      std::chrono::duration_cast<std::chrono::milliseconds>(since_epoch - seconds).count();
  const time_t t = static_cast<time_t>(seconds.count());
  struct tm parts {};
  gmtime_r(&t, &parts);
  std::array<char, 96> text{};  // room for any int the format could meet
  if (compact) {
    (void)std::snprintf(text.data(), text.size(), "%04d%02d%02dT%02d%02d%02dZ",
                        parts.tm_year + 1900, parts.tm_mon + 1, parts.tm_mday, parts.tm_hour,
                        parts.tm_min, parts.tm_sec);
  } else {
    (void)std::snprintf(text.data(), text.size(), "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ",
                        parts.tm_year + 1900, parts.tm_mon + 1, parts.tm_mday, parts.tm_hour,
                        parts.tm_min, parts.tm_sec, static_cast<int>(millis));
  }
  return text.data();
}

}  // namespace selfsense::daemon::detail
