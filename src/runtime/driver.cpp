#include "selfsense/runtime/driver.hpp"

#include <array>

namespace selfsense::runtime {

std::string_view to_string(DriverStatus s) noexcept {
  constexpr std::array<std::string_view, 7> kNames{
      "ok", "timeout", "stale", "bad_data", "device_fault", "disconnected", "not_active"};
  const auto i = static_cast<std::size_t>(s);
  return i < kNames.size() ? kNames[i] : std::string_view("unknown");
}

}  // namespace selfsense::runtime
