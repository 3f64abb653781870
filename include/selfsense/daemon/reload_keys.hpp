// How a reload (SIGHUP, `selfsense ctl reload`; daemon.hpp) treats each key of the daemon's
// configuration (config.hpp), one row per key:
//
//   live            taken by the running loop, armed or not: the PID gains, the filter chain,
//                   the command range (runtime::Tuning)
//   when disarmed   taken only while the loop is disarmed: the model
//   refused         needs a restart: a reload that changes it is refused, naming the key
//
// A row's key is a key path ("control.position.kp") or a section whose keys all share one class
// ("driver": the driver's own keys, compared as the section's text; "control.filters": every
// item). Every key the loader knows (ConfigResult::known_keys) has a row: a test walks them
// (tests/daemon/reload_keys_test.cpp), so a new key cannot reload silently and do nothing.
// Not real-time code.
#pragma once

#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "selfsense/daemon/config.hpp"

namespace selfsense::daemon {

enum class Reload { kLive, kWhenDisarmed, kRefused };

struct ReloadKey {
  std::string_view key{};
  Reload reload{Reload::kRefused};
  // Refused rows: whether the key differs between the running and the reloaded configuration.
  // Live and when-disarmed rows: nullptr (Daemon::reload applies them).
  bool (*changed)(const DaemonConfig& running, const DaemonConfig& next){};
};

// The table, in the order of config.hpp.
[[nodiscard]] std::span<const ReloadKey> reload_keys() noexcept;

// The row of a key path: its own, else the longest row it lies under ("driver.plant" under
// "driver", "control.filters[1].type" under "control.filters"); nullptr when there is none.
[[nodiscard]] const ReloadKey* find_reload_key(std::string_view key_path) noexcept;

// The refused keys whose values differ, in the table's order.
[[nodiscard]] std::vector<std::string> refused_changes(const DaemonConfig& running,
                                                       const DaemonConfig& next);

}  // namespace selfsense::daemon
