#include "selfsense/daemon/reload_keys.hpp"

#include <array>

namespace selfsense::daemon {
namespace {

// Whether the member reached through `kPath` (pointers to members, outermost first) differs.
template <auto... kPath>
bool differs(const DaemonConfig& running, const DaemonConfig& next) {
  return (running.*....*kPath) != (next.*....*kPath);
}

bool never(const DaemonConfig& /*running*/, const DaemonConfig& /*next*/) {
  return false;  // the loader takes one format version only
}

bool driver_section(const DaemonConfig& running, const DaemonConfig& next) {
  // A changed type is named by its own row.
  return running.driver_type == next.driver_type && running.driver_section != next.driver_section;
}

using C = DaemonConfig;
using K = runtime::ControllerConfig;
using P = control::Pid::Params;
using Sh = control::SetpointShaper::Params;
using Dm = control::DampingController::Params;
using S = SafetySection;
using A = AdaptationSection;
using E = adaptation::DriftEstimatorConfig;
using Th = adaptation::ThermalModelConfig;
using H = HealthSection;
using He = adaptation::HealthEstimatorConfig;
using Hb = adaptation::HealthBands;
constexpr Reload kLive = Reload::kLive;
constexpr Reload kRefused = Reload::kRefused;

const std::array kTable{
    ReloadKey{"selfsensed", kRefused, never},
    ReloadKey{"loop.rate_hz", kRefused, differs<&C::loop, &LoopSection::rate_hz>},
    ReloadKey{"loop.priority", kRefused, differs<&C::loop, &LoopSection::priority>},
    ReloadKey{"loop.cpu", kRefused, differs<&C::loop, &LoopSection::cpu>},
    ReloadKey{"loop.cpu_dma_latency_us", kRefused,
              differs<&C::loop, &LoopSection::cpu_dma_latency_us>},
    ReloadKey{"loop.allow_degraded_timing", kRefused,
              differs<&C::loop, &LoopSection::allow_degraded_timing>},
    ReloadKey{"loop.status_period_cycles", kRefused,
              differs<&C::loop, &LoopSection::status_period_cycles>},
    ReloadKey{"model", Reload::kWhenDisarmed, nullptr},
    ReloadKey{"model_state", kRefused, differs<&C::model_state>},
    ReloadKey{"driver.type", kRefused, differs<&C::driver_type>},
    ReloadKey{"driver", kRefused, driver_section},
    ReloadKey{"control.mode", kRefused, differs<&C::control, &K::mode>},
    ReloadKey{"control.feedforward", kRefused, differs<&C::control, &K::feedforward>},
    ReloadKey{"control.command_v_per_m", kLive, nullptr},
    ReloadKey{"control.force_direction", kRefused, differs<&C::control, &K::force_direction>},
    ReloadKey{"control.position.kp", kLive, nullptr},
    ReloadKey{"control.position.ki", kLive, nullptr},
    ReloadKey{"control.position.kd", kLive, nullptr},
    ReloadKey{"control.position.derivative_filter_s", kRefused,
              differs<&C::control, &K::position, &P::derivative_filter_time>},
    ReloadKey{"control.position.setpoint_weight", kRefused,
              differs<&C::control, &K::position, &P::setpoint_weight>},
    ReloadKey{"control.position.tracking_time_s", kRefused,
              differs<&C::control, &K::position, &P::tracking_time>},
    ReloadKey{"control.force.kp", kLive, nullptr},
    ReloadKey{"control.force.ki", kLive, nullptr},
    ReloadKey{"control.force.kd", kLive, nullptr},
    ReloadKey{"control.force.derivative_filter_s", kRefused,
              differs<&C::control, &K::force, &P::derivative_filter_time>},
    ReloadKey{"control.force.setpoint_weight", kRefused,
              differs<&C::control, &K::force, &P::setpoint_weight>},
    ReloadKey{"control.force.tracking_time_s", kRefused,
              differs<&C::control, &K::force, &P::tracking_time>},
    ReloadKey{"control.position_shaper.slew_per_s", kRefused,
              differs<&C::control, &K::position_shaper, &Sh::slew_rate>},
    ReloadKey{"control.position_shaper.filter", kRefused,
              differs<&C::control, &K::position_shaper, &Sh::filter>},
    ReloadKey{"control.position_shaper.time_constant_s", kRefused,
              differs<&C::control, &K::position_shaper, &Sh::time_constant>},
    ReloadKey{"control.force_shaper.slew_per_s", kRefused,
              differs<&C::control, &K::force_shaper, &Sh::slew_rate>},
    ReloadKey{"control.force_shaper.filter", kRefused,
              differs<&C::control, &K::force_shaper, &Sh::filter>},
    ReloadKey{"control.force_shaper.time_constant_s", kRefused,
              differs<&C::control, &K::force_shaper, &Sh::time_constant>},
    ReloadKey{"control.damping.law", kRefused, differs<&C::control, &K::damping, &Dm::law>},
    ReloadKey{"control.damping.gain", kRefused, differs<&C::control, &K::damping, &Dm::gain>},
    ReloadKey{"control.damping.frequency_hz", kRefused,
              differs<&C::control, &K::damping, &Dm::frequency>},
    ReloadKey{"control.damping.damping", kRefused, differs<&C::control, &K::damping, &Dm::damping>},
    ReloadKey{"control.damping.dc_block_hz", kRefused,
              differs<&C::control, &K::damping, &Dm::dc_block_frequency>},
    ReloadKey{"control.filters", kLive, nullptr},
    ReloadKey{"safety.safe_output", kRefused, differs<&C::safety, &S::safe_output>},
    ReloadKey{"safety.safe_value_v_per_m", kRefused, differs<&C::safety, &S::safe_value_v_per_m>},
    ReloadKey{"safety.strain_range", kRefused, differs<&C::safety, &S::strain>},
    ReloadKey{"safety.stress_range_pa", kRefused, differs<&C::safety, &S::stress_pa>},
    ReloadKey{"safety.setpoint_strain", kRefused, differs<&C::safety, &S::setpoint_strain>},
    ReloadKey{"safety.setpoint_stress_pa", kRefused, differs<&C::safety, &S::setpoint_stress_pa>},
    ReloadKey{"safety.overrun.consecutive", kRefused,
              differs<&C::safety, &S::overrun, &runtime::OverrunPolicy::consecutive>},
    ReloadKey{"safety.overrun.within_count", kRefused,
              differs<&C::safety, &S::overrun, &runtime::OverrunPolicy::within_count>},
    ReloadKey{"safety.overrun.window_cycles", kRefused,
              differs<&C::safety, &S::overrun, &runtime::OverrunPolicy::window>},
    ReloadKey{"safety.watchdog_s", kRefused, differs<&C::safety, &S::watchdog_s>},
    ReloadKey{"safety.stop_ramp_s", kRefused, differs<&C::safety, &S::stop_ramp_s>},
    ReloadKey{"recorder.directory", kRefused, differs<&C::recorder, &RecorderSection::directory>},
    ReloadKey{"recorder.rotate_bytes", kRefused,
              differs<&C::recorder, &RecorderSection::rotate_bytes>},
    ReloadKey{"recorder.flush_ms", kRefused, differs<&C::recorder, &RecorderSection::flush_ms>},
    ReloadKey{"recorder.ring_capacity", kRefused,
              differs<&C::recorder, &RecorderSection::ring_capacity>},
    ReloadKey{"recorder.flight_recorder_s", kRefused,
              differs<&C::recorder, &RecorderSection::flight_recorder_s>},
    ReloadKey{"recorder.record_at_start", kRefused,
              differs<&C::recorder, &RecorderSection::record_at_start>},
    ReloadKey{"socket.path", kRefused, differs<&C::socket, &SocketSection::path>},
    ReloadKey{"socket.group", kRefused, differs<&C::socket, &SocketSection::group>},
    ReloadKey{"socket.max_clients", kRefused, differs<&C::socket, &SocketSection::max_clients>},
    ReloadKey{"telemetry.prometheus_file", kRefused,
              differs<&C::telemetry, &TelemetrySection::prometheus_file>},
    ReloadKey{"telemetry.period_s", kRefused, differs<&C::telemetry, &TelemetrySection::period_s>},
    // The learned drift is relative to the running model and read with these coefficients;
    // `ctl adapt freeze|resume` freezes and resumes at run time.
    ReloadKey{"adaptation.enabled", kRefused, differs<&C::adaptation, &A::enabled>},
    ReloadKey{"adaptation.use_temperature", kRefused, differs<&C::adaptation, &A::use_temperature>},
    ReloadKey{"adaptation.feedforward_estimate", kRefused,
              differs<&C::adaptation, &A::feedforward_estimate>},
    ReloadKey{"adaptation.frozen", kRefused, differs<&C::adaptation, &A::estimator, &E::frozen>},
    ReloadKey{"adaptation.learn_loop", kRefused,
              differs<&C::adaptation, &A::estimator, &E::learn_loop>},
    ReloadKey{"adaptation.min_field_step_v_per_m", kRefused,
              differs<&C::adaptation, &A::estimator, &E::min_field_step_v_per_m>},
    ReloadKey{"adaptation.max_interval_s", kRefused,
              differs<&C::adaptation, &A::estimator, &E::max_interval_s>},
    ReloadKey{"adaptation.memory_updates", kRefused,
              differs<&C::adaptation, &A::estimator, &E::memory_updates>},
    ReloadKey{"adaptation.initial_variance", kRefused,
              differs<&C::adaptation, &A::estimator, &E::initial_variance>},
    ReloadKey{"adaptation.process_noise_per_s", kRefused,
              differs<&C::adaptation, &A::estimator, &E::process_noise_per_s>},
    ReloadKey{"adaptation.max_relative_change", kRefused,
              differs<&C::adaptation, &A::estimator, &E::max_relative_change>},
    ReloadKey{"adaptation.reference_degc", kRefused,
              differs<&C::adaptation, &A::estimator, &E::reference_degc>},
    ReloadKey{"adaptation.permittivity_per_k", kRefused,
              differs<&C::adaptation, &A::estimator, &E::permittivity_per_k>},
    ReloadKey{"adaptation.loop_per_k", kRefused,
              differs<&C::adaptation, &A::estimator, &E::loop_per_k>},
    ReloadKey{"adaptation.coupling_per_k", kRefused,
              differs<&C::adaptation, &A::estimator, &E::coupling_per_k>},
    ReloadKey{"adaptation.compliance_per_k", kRefused,
              differs<&C::adaptation, &A::estimator, &E::compliance_per_k>},
    ReloadKey{"adaptation.load_stiffness_ratio", kRefused,
              differs<&C::adaptation, &A::estimator, &E::load_stiffness_ratio>},
    ReloadKey{"adaptation.thermal_model", kRefused,
              differs<&C::adaptation, &A::estimator, &E::thermal, &Th::enabled>},
    ReloadKey{"adaptation.thermal_resistance_k_per_w", kRefused,
              differs<&C::adaptation, &A::estimator, &E::thermal, &Th::resistance_k_per_w>},
    ReloadKey{"adaptation.thermal_time_constant_s", kRefused,
              differs<&C::adaptation, &A::estimator, &E::thermal, &Th::time_constant_s>},
    ReloadKey{"adaptation.ambient_degc", kRefused,
              differs<&C::adaptation, &A::estimator, &E::thermal, &Th::ambient_degc>},
    ReloadKey{"adaptation.stack_volume_m3", kRefused,
              differs<&C::adaptation, &A::estimator, &E::thermal, &Th::stack_volume_m3>},
    ReloadKey{"adaptation.max_power_w", kRefused,
              differs<&C::adaptation, &A::estimator, &E::thermal, &Th::max_power_w>},
    // The health estimate's baseline and trends are learned with these (a restart starts anew).
    ReloadKey{"health.enabled", kRefused, differs<&C::health, &H::enabled>},
    ReloadKey{"health.fault", kRefused, differs<&C::health, &H::bands, &Hb::fault>},
    ReloadKey{"health.max_temperature_degc", kRefused,
              differs<&C::health, &H::bands, &Hb::max_temperature_degc>},
    ReloadKey{"health.max_depolarisation_pct", kRefused,
              differs<&C::health, &H::bands, &Hb::max_depolarisation_pct>},
    ReloadKey{"health.min_leakage_resistivity_ohm_m", kRefused,
              differs<&C::health, &H::bands, &Hb::min_leakage_resistivity_ohm_m>},
    ReloadKey{"health.reversal_field_v_per_m", kRefused,
              differs<&C::health, &H::estimator, &He::reversal_field_v_per_m>},
    ReloadKey{"health.settle_s", kRefused, differs<&C::health, &H::estimator, &He::settle_s>},
    ReloadKey{"health.baseline_cycles", kRefused,
              differs<&C::health, &H::estimator, &He::baseline_cycles>},
    ReloadKey{"health.span_tolerance", kRefused,
              differs<&C::health, &H::estimator, &He::span_tolerance>},
    ReloadKey{"health.hold_field_v_per_m", kRefused,
              differs<&C::health, &H::estimator, &He::hold_field_v_per_m>},
    ReloadKey{"health.hold_settle_s", kRefused,
              differs<&C::health, &H::estimator, &He::hold_settle_s>},
    ReloadKey{"health.hold_window_s", kRefused,
              differs<&C::health, &H::estimator, &He::hold_window_s>},
    ReloadKey{"health.min_hold_field_v_per_m", kRefused,
              differs<&C::health, &H::estimator, &He::min_hold_field_v_per_m>},
    ReloadKey{"health.trend_time_s", kRefused,
              differs<&C::health, &H::estimator, &He::trend_time_s>},
    ReloadKey{"health.slope_time_s", kRefused,
              differs<&C::health, &H::estimator, &He::slope_time_s>},
    ReloadKey{"health.capacitance_per_k", kRefused,
              differs<&C::health, &H::estimator, &He::capacitance_per_k>},
    ReloadKey{"health.dissipation_per_k", kRefused,
              differs<&C::health, &H::estimator, &He::dissipation_per_k>},
    ReloadKey{"health.depolarisation_sensitivity", kRefused,
              differs<&C::health, &H::estimator, &He::depolarisation_sensitivity>},
    ReloadKey{"health.model_reference", kRefused,
              differs<&C::health, &H::estimator, &He::model_reference>},
    ReloadKey{"health.max_span_change", kRefused,
              differs<&C::health, &H::estimator, &He::max_span_change>},
};

// `key_path` is `row` or lies under it ("row.x", "row[i]...").
bool under(std::string_view key_path, std::string_view row) {
  return key_path.starts_with(row) && (key_path.size() == row.size() ||
                                       key_path[row.size()] == '.' || key_path[row.size()] == '[');
}

}  // namespace

std::span<const ReloadKey> reload_keys() noexcept {
  return kTable;
}

const ReloadKey* find_reload_key(std::string_view key_path) noexcept {
  const ReloadKey* best = nullptr;
  for (const ReloadKey& row : kTable) {
    if (under(key_path, row.key) && (best == nullptr || row.key.size() > best->key.size())) {
      best = &row;
    }
  }
  return best;
}

std::vector<std::string> refused_changes(const DaemonConfig& running, const DaemonConfig& next) {
  std::vector<std::string> keys;
  for (const ReloadKey& row : kTable) {
    if (row.reload == Reload::kRefused && row.changed(running, next)) keys.emplace_back(row.key);
  }
  return keys;
}

}  // namespace selfsense::daemon
