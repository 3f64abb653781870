// Real-time path proof for the whole loop: 1e5 cycles with the simulated transducer, in every
// control mode, with a wave, faults, resets and model swaps, make no heap allocation, with a
// hysteresis-creep model and with the daemon's shipped Preisach-class model; and the same with
// the adapted reconstruction (adaptation/adapted_reconstruction.hpp), learning, frozen and
// resumed through the command ring, a swap refused; and with the health estimate and its
// alarms (adaptation/health_estimator.hpp) stepped in every cycle.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <vector>

#include "selfsense/control/filter_design.hpp"
#include "selfsense/control/wave_generator.hpp"
#include "selfsense/drivers/sim/simulated_transducer.hpp"
#include "selfsense/model_io/model_yaml.hpp"
#include "selfsense/runtime/loop.hpp"
#include "support/allocation_counter.hpp"
#include "support/transducer_data.hpp"

namespace selfsense::runtime {
namespace {

static_assert(noexcept(std::declval<Loop&>().cycle(false)));

class CountingSink final : public SampleSink {
 public:
  bool push(const LoopSample& sample) noexcept override {
    last_ = sample;
    ++count_;
    return true;
  }
  std::size_t count_{0};
  LoopSample last_{};
};

void every_mode_without_allocating(const models::TransducerModel& model, bool adapt = false,
                                   bool health = false, bool thermal = false,
                                   bool temperature = false) {
  constexpr double kTs = 1e-4;
  adaptation::DriftEstimatorConfig adapt_config{};
  adapt_config.thermal.enabled = thermal;  // the thermal model carries the estimate (on holds)
  plant::PlantConfig pc;
  pc.sample_rate_hz = 1e4;
  pc.hysteresis.enabled = true;
  pc.creep.enabled = true;
  pc.mechanics.enabled = true;
  pc.mechanics.load_stiffness_n_per_m = 15e6;
  pc.mechanics.resonance_hz = 500.0;
  pc.temperature.enabled = temperature;  // the driver fills temp_ref (the plant's reference)
  drivers::SimulatedTransducer driver(pc);
  std::string why;
  ASSERT_TRUE(driver.configure({kTs}, &why)) << why;
  ASSERT_TRUE(driver.activate(&why));
  ControllerConfig cc;
  cc.position.gains = {1e8, 1e11, 0.0};
  cc.force.gains = {0.005, 10.0, 0.0};
  cc.damping = {control::DampingController::Law::kPositivePosition, 5e8, 500.0, 0.3};
  LoopConfig lc;
  lc.sample_time = kTs;
  lc.stress_min = -1e9;
  lc.stress_max = 1e9;
  lc.strain_min = -1.0;
  lc.strain_max = 1.0;
  lc.adaptation_temperature = temperature;
  lc.adaptation_feedforward_estimate = adapt;  // the estimate's scales into the feedforward
  if (health) {  // bands so narrow that alarms latch (as warnings) and resets clear them
    lc.health_enabled = true;
    lc.health.baseline_cycles = 2;
    lc.health.hold_settle_s = 0.1;
    lc.health.hold_window_s = 0.2;
    lc.health_bands.max_depolarisation_pct = 1e-6;
    lc.health_bands.max_temperature_degc = -100.0;
    lc.health_bands.min_leakage_resistivity_ohm_m = 1e30;
  }
  CountingSink sink;
  std::unique_ptr<Loop> loop_owner =
      adapt ? std::make_unique<Loop>(
                  lc, driver,
                  std::make_unique<adaptation::AdaptedReconstruction>(model, adapt_config, kTs),
                  Controller(cc, model.actuator, kTs), &sink)
            : std::make_unique<Loop>(
                  lc, driver,
                  std::make_unique<models::Reconstruction>(model, models::RuntimeOptions{kTs}),
                  Controller(cc, model.actuator, kTs), &sink);
  Loop& loop = *loop_owner;
  // Prepared outside the loop, as the control thread does.
  auto next_model = std::make_unique<models::Reconstruction>(model, models::RuntimeOptions{kTs});
  auto next_feedforward = std::make_unique<Feedforward>(make_feedforward(cc, model.actuator, kTs));
  control::WaveGenerator::Config wc;
  wc.shape = control::WaveGenerator::Shape::kSine;
  wc.amplitude = 2e-4;
  wc.offset = 6e-4;
  wc.frequency = 5.0;
  auto wave = std::make_unique<control::WaveGenerator>(wc, kTs);

  // A reload's tuning while armed: a notch and a low-pass added, a narrower command range; and
  // back to the configured chain (none) in the next mode.
  Tuning tuned = tuning_of(cc);
  tuned.filters[0] = control::notch({500.0, 2.0, 0.0, 20.0}, kTs);
  tuned.filters[1] = control::low_pass(control::SecondOrderDesign{3000.0, 0.7071}, kTs);
  tuned.filter_count = 2;
  tuned.position = {1.2e8, 1e11, 0.0};
  tuned.command_max = 1.8e6;
  // A state dump's buffer, sized for the running reconstruction.
  models::SavedState state =
      adapt ? adaptation::AdaptedReconstruction(model, adapt_config, kTs).make_saved_state()
            : next_model->make_saved_state();
  // And the health state's, saved with it when health runs.
  std::vector<double> health_state(loop.health_state_size(), 0.0);
  int adapts_done = 0;
  std::uint64_t frozen_updates = 0;
  int tunes_done = 0;
  int states_saved = 0;
  std::uint64_t state_id = 0;
  std::uint64_t tune_id = 0;

  const ControlMode modes[] = {ControlMode::kPosition, ControlMode::kForce, ControlMode::kOpenLoop,
                               ControlMode::kDamping};
  std::uint64_t id = 0;
  {
    test::AllocationCounter counter;
    for (int k = 0; k < 100000; ++k) {
      const int phase = k % 25000;
      const ControlMode mode = modes[k / 25000];
      LoopCommand c{++id, CommandKind::kHeartbeat};
      if (phase == 0) c = {id, CommandKind::kMode, 0.0, mode};
      if (phase == 10) c.kind = CommandKind::kReset;
      if (phase == 20) c.kind = CommandKind::kArm;
      if (phase == 100) c = {id, CommandKind::kSetpoint, mode == ControlMode::kForce ? -6e6 : 5e-4};
      if (k == 5000) c = {id, CommandKind::kWave, 0.0, mode, wave.release()};
      if (phase == 10000) {
        c = {id, CommandKind::kTune};
        c.tuning = (k / 25000) % 2 == 0 ? tuned : tuning_of(cc);
        tune_id = id;
      }
      if (phase == 15000) {
        c = {id, CommandKind::kSaveState};
        c.state = &state;
        c.health_state = health_state;
        state_id = id;
      }
      if (phase == 20000) c = {id, CommandKind::kRampDown, 0.05};  // a ramped stop in each mode
      if (k == 25003) c.kind = CommandKind::kDisarm;               // a swap is refused while armed
      if (k == 25005) {
        c = {id, CommandKind::kSwapModel, 0.0, mode, nullptr, next_model.release()};
        c.feedforward = next_feedforward.release();
      }
      if (k == 30000 || k == 42000) c = {id, CommandKind::kAdapt, k == 30000 ? 1.0 : 0.0};
      if (k == 60000) {
        ASSERT_TRUE(driver.inject(plant::FaultKind::nan_sample, plant::Channel::d, 1, 3));
      }
      if (c.kind != CommandKind::kHeartbeat || k % 1000 == 0) {
        ASSERT_TRUE(loop.submit(c));
      }
      loop.cycle(k % 5000 == 4999);
      LoopAnswer a;
      while (loop.take_answer(a)) {
        if (a.id == tune_id && a.result == CommandResult::kDone) ++tunes_done;
        if (a.id == state_id && a.result == CommandResult::kDone) ++states_saved;
        if (a.result == CommandResult::kDone && k >= 30000 && k <= 30002) ++adapts_done;
      }
      if (k == 30100) frozen_updates = loop.local_status().adaptation.updates;
      // Frozen from 30000 to 42000: not one update.
      if (adapt && k == 41999) {
        ASSERT_EQ(loop.local_status().adaptation.updates, frozen_updates);
        ASSERT_TRUE(loop.local_status().adaptation.frozen);
      }
    }
    EXPECT_EQ(counter.count(), 0U);
    EXPECT_EQ(counter.locks(), 0U);
  }
  EXPECT_EQ(tunes_done, 4);
  EXPECT_EQ(states_saved, 4);
  Retired r;
  while (loop.take_retired(r)) {
    delete r.wave;
    delete r.model;
    delete r.feedforward;
  }
  EXPECT_EQ(sink.count_, 100000U);
  EXPECT_GT(loop.local_status().commands, 10U);
  // Under adaptation a swap is refused (the learned drift is the running model's) and the
  // model handed back.
  EXPECT_EQ(loop.local_status().model_swaps, adapt ? 0U : 1U);
  const AdaptationStatus& a = loop.local_status().adaptation;
  EXPECT_EQ(a.enabled, adapt);
  if (adapt) {
    EXPECT_EQ(adapts_done, 1);
    EXPECT_FALSE(a.frozen);
    EXPECT_TRUE(std::isfinite(a.temperature_degc));
  }
  if (adapt && !temperature) {
    EXPECT_GT(a.updates, frozen_updates);
    EXPECT_GT(frozen_updates, 50U);
  }
  if (temperature) {  // the measured temperature replaced the estimate: nothing learned
    EXPECT_EQ(a.updates, 0U);
    const LoopSample& last = loop.local_status().last;
    ASSERT_TRUE(std::isfinite(last.temp_ref));
    EXPECT_EQ(last.temp_equivalent, last.temp_ref);
  }
  const HealthStatus& h = loop.local_status().health;
  EXPECT_EQ(h.enabled, health);
  if (health) {
    EXPECT_GT(h.figures.cycles, 0U);
    EXPECT_TRUE(h.figures.has_capacitance);
    EXPECT_NE(h.latched, 0U);
    EXPECT_EQ(loop.supervisor().record(Fault::kHealth).count, 0U);  // warnings, not faults
    EXPECT_EQ(health_state.size(), Loop::kHealthStateSize);
    EXPECT_NE(health_state[0], 0.0);  // the sample count: the dumps wrote it
  }
}

TEST(LoopRealTime, CyclesInEveryModeDoNotAllocate) {
  every_mode_without_allocating(test::typical_transducer(1e-3));
}

// The daemon's shipped model: hinges on its plays, so the feedforward's inverse is solved per
// sample (operators/hysteresis_creep.hpp).
TEST(LoopRealTime, CyclesInEveryModeDoNotAllocateWithTheShippedPreisachModel) {
  const models::TransducerModel model =
      models::load_model(std::filesystem::path(SELFSENSE_SOURCE_DIR) / "config/models/sim.yaml");
  ASSERT_TRUE(model.actuator.has_value());
  ASSERT_FALSE(model.actuator->op.hinges.weights.empty());
  every_mode_without_allocating(model);
}

TEST(LoopRealTime, CyclesInEveryModeDoNotAllocateWithAdaptation) {
  every_mode_without_allocating(test::typical_transducer(1e-3), true);
}

TEST(LoopRealTime, CyclesInEveryModeDoNotAllocateWithAdaptationAndTheShippedPreisachModel) {
  every_mode_without_allocating(
      models::load_model(std::filesystem::path(SELFSENSE_SOURCE_DIR) / "config/models/sim.yaml"),
      true);
}

TEST(LoopRealTime, CyclesInEveryModeDoNotAllocateWithAdaptationAndTheThermalModel) {
  every_mode_without_allocating(test::typical_transducer(1e-3), true, false, true);
}

// The driver's temperature fed to the adapted reconstruction with the model's fitted temperature
// coefficients (adaptation.use_temperature).
TEST(LoopRealTime, CyclesInEveryModeDoNotAllocateWithAdaptationAndTheMeasuredTemperature) {
  models::TransducerModel model = test::typical_transducer(1e-3);
  models::TemperatureCoefficients t;
  t.sensor = {{4e-3, -1e-6}, {-3e-3, 0.0}, {2e-3, 0.0}};
  t.actuator = {{2e-3, 0.0}, {-3e-3, 0.0}, {5e-4, 0.0}};
  model.temperature = t;
  every_mode_without_allocating(model, true, false, false, true);
}

TEST(LoopRealTime, CyclesInEveryModeDoNotAllocateWithHealth) {
  every_mode_without_allocating(test::typical_transducer(1e-3), false, true);
}

TEST(LoopRealTime, CyclesInEveryModeDoNotAllocateWithHealthAndAdaptation) {
  every_mode_without_allocating(
      models::load_model(std::filesystem::path(SELFSENSE_SOURCE_DIR) / "config/models/sim.yaml"),
      true, true);
}

}  // namespace
}  // namespace selfsense::runtime
