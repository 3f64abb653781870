#include "selfsense/drivers/sim/simulated_transducer.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

#include "selfsense/plant/status.hpp"

namespace selfsense::drivers {

SimulatedTransducer::SimulatedTransducer(plant::PlantConfig config, TemperatureRamp temperature)
    : config_(std::move(config)), ramp_(temperature), temperature_degc_(temperature.start_degc) {}

bool SimulatedTransducer::configure(const runtime::DriverSetup& setup, std::string* why) {
  const double ratio = config_.sample_rate_hz * setup.sample_time;
  const double whole = std::round(ratio);
  if (!(whole >= 1.0) || std::abs(ratio - whole) > 1e-9 * whole) {
    if (why != nullptr) {
      *why = "driver.plant.sample_rate_hz: " + std::to_string(config_.sample_rate_hz) +
             " Hz is not a whole multiple of the loop rate " +
             std::to_string(1.0 / setup.sample_time) + " Hz";
    }
    return false;
  }
  std::string invalid;
  if (!config_.is_valid(&invalid)) {
    if (why != nullptr) *why = "driver." + invalid;
    return false;
  }
  substeps_ = static_cast<int>(whole);
  sample_time_ = setup.sample_time;
  plant_ = std::make_unique<plant::Plant>(config_);
  return true;
}

bool SimulatedTransducer::activate(std::string* why) {
  if (!plant_) {
    if (why != nullptr) *why = "simulated transducer: activate() before configure()";
    return false;
  }
  active_ = true;
  command_ = 0.0;
  return true;
}

runtime::DriverStatus SimulatedTransducer::read(runtime::InputSample& out) noexcept {
  if (!active_) return runtime::DriverStatus::kNotActive;
  ++counters_.reads;
  // A pulse from apply() lasts while this cycle is before its end (cycle_published_ is the
  // count of cycles read so far: the pulse starts with the next read after apply()).
  const bool pulse = cycles_ < pulse_end_cycle_.load(std::memory_order_acquire);
  const double force = force_n_.load(std::memory_order_relaxed) +
                       (pulse ? pulse_n_.load(std::memory_order_relaxed) : 0.0);
  const double t = static_cast<double>(cycles_) * sample_time_;
  const double share = ramp_.ramp_s > 0.0 ? std::min(1.0, t / ramp_.ramp_s) : 1.0;
  const double ambient_degc =
      ramp_.start_degc + (ramp_.end_degc - ramp_.start_degc) * share +
      ramp_.swing_degc * std::sin(2.0 * std::numbers::pi * t / ramp_.swing_period_s);
  const plant::StepInput input{command_, force, ambient_degc};
  plant::StepOutput o{};
  // The plant may run several steps per loop cycle; a fault flag raised in any of them is the
  // device's (like the sticky bits of a status register), not only one in the step read last.
  std::uint32_t status = 0;
  double latency_s = 0.0;
  for (int i = 0; i < substeps_; ++i) {
    o = plant_->step(input);
    status |= o.status;
    latency_s = std::max(latency_s, o.latency_s);
  }
  temperature_degc_ = o.temp_degc;  // with the plant's self-heating
  ++cycles_;
  cycle_published_.store(cycles_, std::memory_order_relaxed);
  out.e = o.e_meas_v_per_m;
  out.d = o.d_meas_c_per_m2;
  out.s_ref = o.s;
  out.t_ref = o.t_pa;
  if (has_temperature()) out.temp_ref = o.temp_degc;
  out.timestamp_ns = static_cast<std::int64_t>(std::llround(o.t_s * 1e9));
  out.device_status = static_cast<std::uint16_t>(status & 0xffffU);
  // Each fault flag of the cycle counts under its own name (the status below takes the first).
  const auto flagged = [status](std::uint32_t bit, std::uint64_t& n) {
    if ((status & bit) != 0U) ++n;
  };
  flagged(plant::kAmplifierFault, causes_.amplifier_fault);
  flagged(plant::kStuckAdc, causes_.stuck_adc);
  flagged(plant::kMissedDataReady, causes_.missed_data_ready);
  flagged(plant::kNanSample, causes_.nan_sample);
  flagged(plant::kOutOfRange, causes_.out_of_range);
  flagged(plant::kSensorDisconnect, causes_.sensor_disconnect);
  if ((status & plant::kAmplifierFault) != 0U) {
    ++counters_.device_faults;
    return runtime::DriverStatus::kDeviceFault;
  }
  // A sample delivered a loop period or more after its sampling instant missed its cycle.
  if (latency_s >= sample_time_) {
    ++counters_.timeouts;
    return runtime::DriverStatus::kTimeout;
  }
  if ((status & (plant::kStuckAdc | plant::kMissedDataReady)) != 0U) {
    ++counters_.stale;
    return runtime::DriverStatus::kStale;
  }
  if ((status & (plant::kNanSample | plant::kOutOfRange | plant::kSensorDisconnect)) != 0U) {
    ++counters_.bad_data;
    return runtime::DriverStatus::kBadData;
  }
  return runtime::DriverStatus::kOk;
}

runtime::DriverStatus SimulatedTransducer::write(const runtime::OutputCommand& command) noexcept {
  if (!active_) return runtime::DriverStatus::kNotActive;
  ++counters_.writes;
  command_ = std::isfinite(command.e) ? command.e : 0.0;
  return runtime::DriverStatus::kOk;
}

void SimulatedTransducer::deactivate() noexcept {
  command_ = 0.0;
  active_ = false;
}

runtime::DriverCounters SimulatedTransducer::counters() const noexcept {
  runtime::DriverCounters c = counters_;
  c.add_event("amplifier_fault_cycles", causes_.amplifier_fault);
  c.add_event("stuck_adc_cycles", causes_.stuck_adc);
  c.add_event("missed_data_ready_cycles", causes_.missed_data_ready);
  c.add_event("nan_sample_cycles", causes_.nan_sample);
  c.add_event("out_of_range_cycles", causes_.out_of_range);
  c.add_event("sensor_disconnect_cycles", causes_.sensor_disconnect);
  return c;
}

bool SimulatedTransducer::inject(plant::FaultKind kind, plant::Channel channel,
                                 std::int64_t after_cycles, std::int64_t cycles) noexcept {
  if (!plant_) return false;
  const std::int64_t now = plant_->save().sample;
  return plant_->inject(kind, channel, now + after_cycles * substeps_, cycles * substeps_);
}

void SimulatedTransducer::apply(double newtons, double seconds) noexcept {
  const auto cycles = std::max<std::int64_t>(1, std::llround(seconds / sample_time_));
  // Force first, then the end that makes it visible (release; the loop's read acquires).
  pulse_n_.store(newtons, std::memory_order_relaxed);
  pulse_end_cycle_.store(cycle_published_.load(std::memory_order_relaxed) + cycles,
                         std::memory_order_release);
}

}  // namespace selfsense::drivers
