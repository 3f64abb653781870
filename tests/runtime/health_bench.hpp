// The health tests' bench: runtime::Loop with the adapted reconstruction (the shipped model
// config/models/sim.yaml, the mount's ratio 0.21) and the health estimate on the daemon's
// simulated bench (config/plant/daemon.yaml with the temperature model), in simulated time.
// At 1 kHz, not 10 and 20 kHz, for CI time: the mount's resonance (2 kHz) is left out (the load
// spring acts quasi-statically) and the model identified at 20 kHz runs at 1 kHz
// (health_aging_test.cpp says the same).
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <memory>
#include <string>

#include "loop_commands.hpp"
#include "selfsense/adaptation/adapted_reconstruction.hpp"
#include "selfsense/control/wave_generator.hpp"
#include "selfsense/drivers/sim/simulated_transducer.hpp"
#include "selfsense/model_io/model_yaml.hpp"
#include "selfsense/plant_io/plant_yaml.hpp"
#include "selfsense/runtime/loop.hpp"

namespace selfsense::runtime::test {

inline constexpr double kHealthTs = 1e-3;  // [s]

struct HealthBenchOptions {
  drivers::TemperatureRamp temperature{};
  double polarisation_loss_per_h{0.0};  // plant.aging from aging_start_s on; 0: no aging
  double aging_start_s{120.0};
  ControlMode mode{ControlMode::kOpenLoop};
  LoopConfig loop{};  // sample time, ranges and health_enabled are set by the bench
};

// The bench's coefficients (docs/health.md, HealthAging.DISABLED_Calibration).
inline LoopConfig health_loop_config() {
  LoopConfig lc;
  lc.status_period = 100;
  lc.health.capacitance_per_k = 4.03e-3;
  lc.health.dissipation_per_k = -3.78e-3;
  lc.health.depolarisation_sensitivity = 0.76;
  return lc;
}

inline plant::PlantConfig health_plant(double polarisation_loss_per_h, double aging_start_s) {
  const std::filesystem::path root(SELFSENSE_SOURCE_DIR);
  plant::PlantConfig pc = plant::load_plant_file(root / "config/plant/daemon.yaml").plant;
  pc.sample_rate_hz = 1.0 / kHealthTs;
  pc.mechanics.enabled = false;
  pc.temperature.enabled = true;  // the coefficients of config/plant/temperature.yaml
  pc.aging.enabled = polarisation_loss_per_h > 0.0;
  pc.aging.polarisation_loss_per_h = polarisation_loss_per_h;
  pc.aging.start_s = aging_start_s;
  return pc;
}

// The bench's loop on `driver`: the shipped model's adapted reconstruction (the mount's ratio
// 0.21) with the health estimate; `lc`'s sample time, ranges and health_enabled are set here.
inline std::unique_ptr<Loop> health_loop(LoopConfig lc, drivers::SimulatedTransducer& driver,
                                         const ControllerConfig& cc) {
  const std::filesystem::path root(SELFSENSE_SOURCE_DIR);
  const models::TransducerModel model = models::load_model(root / "config/models/sim.yaml");
  adaptation::DriftEstimatorConfig ec;
  ec.load_stiffness_ratio = 0.21;  // config/sim.yaml's bench
  lc.sample_time = kHealthTs;
  lc.strain_min = -1.0;
  lc.strain_max = 1.0;
  lc.stress_min = -1e9;
  lc.stress_max = 1e9;
  lc.health_enabled = true;
  return std::make_unique<Loop>(
      lc, driver, std::make_unique<adaptation::AdaptedReconstruction>(model, ec, kHealthTs),
      Controller(cc, model.actuator, kHealthTs), nullptr);
}

struct HealthBench {
  explicit HealthBench(const HealthBenchOptions& o)
      : driver(health_plant(o.polarisation_loss_per_h, o.aging_start_s), o.temperature) {
    std::string why;
    EXPECT_TRUE(driver.configure({kHealthTs}, &why)) << why;
    EXPECT_TRUE(driver.activate(&why)) << why;
    ControllerConfig cc;
    cc.mode = o.mode;
    // Position on the self-sensed strain: plant gain about 6e-10 strain per V/m.
    cc.position.gains = {2e8, 2.5e11, 0.0};
    cc.position.tracking_time = 1e-2;
    cc.position_shaper.slew_rate = 0.05;
    loop = health_loop(o.loop, driver, cc);
  }
  HealthBench(const HealthBench&) = delete;
  HealthBench& operator=(const HealthBench&) = delete;
  HealthBench(HealthBench&&) = delete;
  HealthBench& operator=(HealthBench&&) = delete;
  ~HealthBench() {
    Retired r;
    while (loop->take_retired(r)) {
      delete r.wave;
      delete r.model;
      delete r.feedforward;
    }
  }

  // Submits and runs cycles until the loop answered.
  CommandResult send(LoopCommand c) { return selfsense::test::send_and_cycle(*loop, next_id, c); }
  void wave(const control::WaveGenerator::Config& wc) {
    EXPECT_EQ(send({0, CommandKind::kWave, 0.0, loop->controller().mode(),
                    std::make_unique<control::WaveGenerator>(wc, kHealthTs).release()}),
              CommandResult::kDone);
  }
  void run(double seconds) const {
    const auto n = static_cast<long>(seconds / kHealthTs);
    for (long k = 0; k < n; ++k)
      loop->cycle(false);
  }
  [[nodiscard]] const HealthStatus& health() const { return loop->local_status().health; }

  drivers::SimulatedTransducer driver;
  std::unique_ptr<Loop> loop;
  std::uint64_t next_id{0};
};

// A strain sine, 1e-4 .. 1.1e-3 at 2 Hz unless said (the aging proof's drive).
inline control::WaveGenerator::Config strain_sine(double amplitude = 5e-4, double offset = 6e-4,
                                                  double frequency_hz = 2.0) {
  control::WaveGenerator::Config wc;
  wc.amplitude = amplitude;
  wc.offset = offset;
  wc.frequency = frequency_hz;
  return wc;
}

}  // namespace selfsense::runtime::test
