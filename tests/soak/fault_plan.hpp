// The soak test's fault schedule: which fault, from which loop cycle, for how long, and what the
// daemon must show for it. Plant faults go into the simulated bench's `faults:` table (plant
// time is loop cycles times the period, so a fault's first cycle is known exactly); watchdog
// items are played by the soak driver (it stops the wave and sends no setpoint).
//
// One round of items, repeated over the run: every plant fault kind (the simulated transducer
// turns them into the driver statuses stale, bad data, device fault and timeout), a late sample
// that stays within its cycle (not a fault: it must not trip anything) and the setpoint watchdog.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "selfsense/plant/config.hpp"

namespace selfsense::soak {

enum class Source : std::uint8_t { kPlant, kWatchdog };

struct PlannedFault {
  std::string name{};  // "nan_sample(d)", "watchdog"
  Source source{Source::kPlant};
  plant::FaultKind kind{plant::FaultKind::nan_sample};
  plant::Channel channel{plant::Channel::d};
  std::int64_t start_cycle{0};  // plant: the first loop cycle that reads it; watchdog: from when
                                // the driver stops the wave
  std::int64_t cycles{1};       // loop cycles it lasts (plant)
  double late_by_s{0.0};        // late_sample only
  std::uint32_t plant_bit{0};   // plant status bit the recording's driver_status shows
  std::uint32_t loop_fault{0};  // runtime::bit(Fault) expected to latch; 0: must not fault
};

struct PlanSettings {
  double seconds{75.0};     // the run
  double rate_hz{10000.0};  // the loop
  double first_s{4.0};      // the first item (after start, reset and arm)
  double spacing_s{2.5};    // between items, at least (widened so plant items fit the table)
  double quiet_end_s{4.0};  // no item in the run's last seconds
};

// Items in start order.
[[nodiscard]] std::vector<PlannedFault> make_plan(const PlanSettings& settings);

// The plant items as the entries of a plant configuration's `faults:` list, indented for
// `plant:`: "  faults:\n    - {kind: ..., channel: ..., start_s: ..., ...}\n".
[[nodiscard]] std::string plant_faults_yaml(const std::vector<PlannedFault>& plan, double rate_hz);

}  // namespace selfsense::soak
