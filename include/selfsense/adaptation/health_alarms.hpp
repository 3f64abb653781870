// Alarm bands on the health figures (health_estimator.hpp) and the equivalent temperature
// (drift_estimator.hpp), latched until reset (docs/health.md):
//   overheating     theta_eq > max_temperature_degc                 (needs the adaptation)
//   depolarisation  100 loss > max_depolarisation_pct               (the slow loss of polarisation)
//   insulation      rho < min_leakage_resistivity_ohm_m             (the slow leakage, from holds)
// An alarm is raised by the first evaluation beyond its band and stays latched, with the time
// it was first raised, until reset() at a moment its figure is back inside the band. Whether an
// alarm is a warning or a fault is the caller's (HealthBands::fault).
// Real-time safe: evaluate(), reset() and the state's save and restore are noexcept and
// allocation-free.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "selfsense/adaptation/health_estimator.hpp"

namespace selfsense::adaptation {

enum class HealthAlarm : std::uint8_t { kOverheating, kDepolarisation, kInsulation, kCount };
inline constexpr std::size_t kHealthAlarmCount = static_cast<std::size_t>(HealthAlarm::kCount);
[[nodiscard]] constexpr std::uint32_t bit(HealthAlarm a) noexcept {
  return 1U << static_cast<unsigned>(a);
}
// "overheating", "depolarisation", "insulation" (status JSON and Prometheus labels).
[[nodiscard]] std::string_view to_string(HealthAlarm a) noexcept;

struct HealthBands {
  double max_temperature_degc{80.0};            // [degC]
  double max_depolarisation_pct{3.0};           // [%]
  double min_leakage_resistivity_ohm_m{1.0e9};  // [Ohm m]; R C_stack = rho eps = 20 s
  bool fault{false};                            // true: an alarm is also a fault of the loop

  // Finite; depolarisation in (0, 100); resistivity > 0. *why names the key under `prefix`.
  [[nodiscard]] bool is_valid(const std::string& prefix, std::string* why) const;
  friend bool operator==(const HealthBands&, const HealthBands&) = default;
};

class HealthAlarms final {
 public:
  explicit HealthAlarms(const HealthBands& bands) noexcept : bands_{bands} {}

  // The alarms beyond their bands now (bits); each latches. has_temperature false: no
  // equivalent temperature (no adaptation), overheating is not judged.
  std::uint32_t evaluate(const HealthFigures& f, bool has_temperature, double temperature_degc,
                         double t_s) noexcept;
  [[nodiscard]] std::uint32_t active() const noexcept { return active_; }
  [[nodiscard]] std::uint32_t latched() const noexcept { return latched_; }
  // When the latched alarm was first raised [s]; negative when not latched.
  [[nodiscard]] double raised_at_s(HealthAlarm a) const noexcept {
    return raised_at_s_[static_cast<std::size_t>(a)];
  }
  // Clears the latched alarms that are not active; returns those still latched.
  std::uint32_t reset() noexcept;
  // The latched alarms and when each was raised (4 values: the latched bits, then raised_at_s
  // per alarm), so that a restart keeps the warnings; the active bits are evaluated anew. A
  // span shorter than kStateSize is left alone / ignored.
  static constexpr std::size_t kStateSize{1 + kHealthAlarmCount};
  void save_state(std::span<double> out) const noexcept;
  void restore_state(std::span<const double> in) noexcept;
  [[nodiscard]] const HealthBands& bands() const noexcept { return bands_; }

 private:
  HealthBands bands_;
  std::uint32_t active_{0};
  std::uint32_t latched_{0};
  std::array<double, kHealthAlarmCount> raised_at_s_{-1.0, -1.0, -1.0};
};

}  // namespace selfsense::adaptation
