// The simulated transducer (selfsense::plant) as a driver of the loop: the first
// implementation of runtime::Driver and the one CI runs, with the plant's fault-injection API
// behind it.
//
// Timing: the plant runs `substeps` samples per loop cycle (its rate divided by the loop's, an
// integer: the loop rate must divide the ADC rate). write(E) holds E for the next cycle (zero
// order hold, like a DAC); read() advances the plant by one cycle with the held command and the
// external force, and returns the last substep's measured E and D, with the true S and T as
// reference channels.
//
// Faults: a plant status bit raised in any of the cycle's plant samples becomes a driver
// status: stuck ADC and missed data-ready -> kStale, NaN, out-of-range and disconnected
// channels -> kBadData (the values are passed on too, so the loop's own checks see them),
// amplifier fault line -> kDeviceFault, a sample late by a loop period or more -> kTimeout (it
// missed its cycle; one late by less arrived within it and only shows in the status bits).
// counters() adds, as events, the cycles in which each fault flag was raised
// (`amplifier_fault_cycles`, `stuck_adc_cycles`, `missed_data_ready_cycles`,
// `nan_sample_cycles`, `out_of_range_cycles`, `sensor_disconnect_cycles`); counters() reads
// plain fields: call it from the loop's thread (the loop does, for its status snapshot).
//
// Temperature (the driver section's `temperature: {start_degc, end_degc, ramp_s}`): the stack's
// temperature at loop time t = cycles * Ts since activate() [degC],
//   theta(t) = start + (end - start) min(1, t / ramp_s)     (ramp_s 0: end from the start)
//              + swing_degc sin(2 pi t / swing_period_s)      (swing_degc 0: none)
// fed to the plant's temperature model (plant.temperature, which must be enabled): a stack that
// warms while the daemon runs, for the online adaptation (docs/adaptation.md). Default 25 degC.
//
// read(), write(), inject(), set_external_force() are real-time safe.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "selfsense/plant/config.hpp"
#include "selfsense/plant/plant.hpp"
#include "selfsense/runtime/driver.hpp"

namespace selfsense::drivers {

// The stack's temperature while the daemon runs (header comment).
struct TemperatureRamp {
  double start_degc{25.0};
  double end_degc{25.0};
  double ramp_s{0.0};            // [s] >= 0
  double swing_degc{0.0};        // amplitude of a sine on top of the ramp [K]
  double swing_period_s{600.0};  // its period [s] > 0
  friend bool operator==(const TemperatureRamp&, const TemperatureRamp&) = default;
};

class SimulatedTransducer final : public runtime::Driver, public runtime::ForceInput {
 public:
  explicit SimulatedTransducer(plant::PlantConfig config, TemperatureRamp temperature = {});

  [[nodiscard]] std::string_view name() const noexcept override { return "simulated"; }
  bool configure(const runtime::DriverSetup& setup, std::string* why) override;
  bool activate(std::string* why) override;
  runtime::DriverStatus read(runtime::InputSample& out) noexcept override;
  runtime::DriverStatus write(const runtime::OutputCommand& command) noexcept override;
  void deactivate() noexcept override;
  [[nodiscard]] bool has_references() const noexcept override { return true; }
  // The stack's temperature (the ramp and swing, with the self-heating) when the plant models
  // temperature or heats itself.
  [[nodiscard]] bool has_temperature() const noexcept override {
    return config_.temperature.enabled || config_.heating.enabled;
  }
  [[nodiscard]] runtime::DriverCounters counters() const noexcept override;
  [[nodiscard]] runtime::ForceInput* force_input() noexcept override { return this; }
  // A force pulse on the stack (ForceInput), on top of set_external_force(); any thread.
  void apply(double newtons, double seconds) noexcept override;

  // Test bench: an external force [N] on the stack (a load step, an impulse), any thread.
  void set_external_force(double newtons) noexcept {
    force_n_.store(newtons, std::memory_order_relaxed);
  }
  // Fault injection, starting `after_cycles` loop cycles from now, lasting `cycles` cycles.
  bool inject(plant::FaultKind kind, plant::Channel channel, std::int64_t after_cycles,
              std::int64_t cycles) noexcept;

  [[nodiscard]] const plant::Plant& plant() const noexcept { return *plant_; }
  [[nodiscard]] double command() const noexcept { return command_; }
  [[nodiscard]] int substeps() const noexcept { return substeps_; }
  // The stack's temperature in the cycle read last [degC].
  [[nodiscard]] double temperature_degc() const noexcept { return temperature_degc_; }

 private:
  plant::PlantConfig config_;
  TemperatureRamp ramp_;
  double temperature_degc_{25.0};
  std::unique_ptr<plant::Plant> plant_{};
  int substeps_{1};
  double sample_time_{0.0};
  bool active_{false};
  double command_{0.0};
  std::int64_t cycles_{0};
  std::atomic<double> force_n_{0.0};
  // The pulse: its force, and the loop cycle it ends before (cycles_ as published for it).
  std::atomic<double> pulse_n_{0.0};
  std::atomic<std::int64_t> pulse_end_cycle_{0};
  std::atomic<std::int64_t> cycle_published_{0};
  runtime::DriverCounters counters_{};
  // Cycles in which each plant fault flag was raised (counters() events *_cycles).
  struct Causes {
    std::uint64_t amplifier_fault{0};
    std::uint64_t stuck_adc{0};
    std::uint64_t missed_data_ready{0};
    std::uint64_t nan_sample{0};
    std::uint64_t out_of_range{0};
    std::uint64_t sensor_disconnect{0};
  };
  Causes causes_{};
};

}  // namespace selfsense::drivers
