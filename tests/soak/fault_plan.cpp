#include "soak/fault_plan.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include "selfsense/plant/status.hpp"
#include "selfsense/runtime/supervisor.hpp"

namespace selfsense::soak {
namespace {

using plant::Channel;
using plant::FaultKind;
using runtime::Fault;

// One round; durations in loop cycles at 10 kHz (scaled by the rate below).
struct Item {
  const char* name;
  Source source;
  FaultKind kind;
  Channel channel;
  double seconds;       // 0: a single plant sample
  double late_periods;  // late_sample: how late, in loop periods
  std::uint32_t plant_bit;
  Fault fault;
  bool faults;
};

constexpr std::array<Item, 9> kRound{{
    {"nan_sample(d)", Source::kPlant, FaultKind::nan_sample, Channel::d, 0.0, 0.0,
     plant::kNanSample, Fault::kDriverError, true},
    {"stuck_adc(d)", Source::kPlant, FaultKind::stuck_adc, Channel::d, 0.05, 0.0, plant::kStuckAdc,
     Fault::kStaleSample, true},
    {"out_of_range(e)", Source::kPlant, FaultKind::out_of_range, Channel::e, 0.0, 0.0,
     plant::kOutOfRange, Fault::kDriverError, true},
    {"missed_data_ready", Source::kPlant, FaultKind::missed_data_ready, Channel::both, 0.002, 0.0,
     plant::kMissedDataReady, Fault::kStaleSample, true},
    {"late_sample(1.5 periods)", Source::kPlant, FaultKind::late_sample, Channel::both, 0.001, 1.5,
     plant::kLateSample, Fault::kDriverTimeout, true},
    {"watchdog", Source::kWatchdog, FaultKind::nan_sample, Channel::both, 0.0, 0.0, 0,
     Fault::kWatchdog, true},
    {"sensor_disconnect(d)", Source::kPlant, FaultKind::sensor_disconnect, Channel::d, 0.05, 0.0,
     plant::kSensorDisconnect, Fault::kDriverError, true},
    {"amplifier_fault", Source::kPlant, FaultKind::amplifier_fault, Channel::both, 0.1, 0.0,
     plant::kAmplifierFault, Fault::kAmplifierFault, true},
    {"late_sample(0.5 periods, no fault)", Source::kPlant, FaultKind::late_sample, Channel::both,
     0.001, 0.5, plant::kLateSample, Fault::kCount, false},
}};

}  // namespace

std::vector<PlannedFault> make_plan(const PlanSettings& s) {
  const std::size_t plant_per_round = static_cast<std::size_t>(std::count_if(
      kRound.begin(), kRound.end(), [](const Item& i) { return i.source == Source::kPlant; }));
  const double usable = s.seconds - s.first_s - s.quiet_end_s;
  const auto max_items = static_cast<std::size_t>(static_cast<double>(plant::kMaxScheduledFaults) *
                                                  static_cast<double>(kRound.size()) /
                                                  static_cast<double>(plant_per_round));
  const double spacing =
      std::max(s.spacing_s, usable / static_cast<double>(std::max<std::size_t>(max_items, 1)));
  std::vector<PlannedFault> plan;
  std::size_t plant_items = 0;
  for (std::size_t n = 0;; ++n) {
    const double start_s = s.first_s + spacing * static_cast<double>(n);
    if (start_s > s.seconds - s.quiet_end_s) break;
    const Item& item = kRound[n % kRound.size()];
    if (item.source == Source::kPlant && ++plant_items > plant::kMaxScheduledFaults) break;
    PlannedFault f;
    f.name = item.name;
    f.source = item.source;
    f.kind = item.kind;
    f.channel = item.channel;
    f.start_cycle = std::llround(start_s * s.rate_hz);
    f.cycles = std::max<std::int64_t>(1, std::llround(item.seconds * s.rate_hz));
    f.late_by_s = item.late_periods / s.rate_hz;
    f.plant_bit = item.plant_bit;
    f.loop_fault = item.faults ? runtime::bit(item.fault) : 0U;
    plan.push_back(f);
  }
  return plan;
}

std::string plant_faults_yaml(const std::vector<PlannedFault>& plan, double rate_hz) {
  std::string text = "  faults:\n";
  for (const PlannedFault& f : plan) {
    if (f.source != Source::kPlant) continue;
    // Cycle k reads the plant samples from (k - 1) periods on: the fault starts there.
    const double start_s = static_cast<double>(f.start_cycle - 1) / rate_hz;
    // nan_sample and out_of_range: one plant sample (duration 0); the rest whole cycles.
    const bool single = f.kind == FaultKind::nan_sample || f.kind == FaultKind::out_of_range;
    const double duration_s = single ? 0.0 : static_cast<double>(f.cycles) / rate_hz;
    std::array<char, 256> line{};
    static_cast<void>(std::snprintf(line.data(), line.size(),
                                    "    - {kind: %s, channel: %s, start_s: %.17g, "
                                    "duration_s: %.17g, late_by_s: %.17g}\n",
                                    plant::to_string(f.kind), plant::to_string(f.channel), start_s,
                                    duration_s, f.late_by_s));
    text += line.data();
  }
  return text;
}

}  // namespace selfsense::soak
