// The loop against the simulated transducer in simulated time: tracking on the self-sensed
// signals only (the plant's true S and T are read for the figures, never by the loop), damping,
// and every fault reaching the safe output in the cycle it occurs.
#include "selfsense/runtime/loop.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "loop_commands.hpp"
#include "selfsense/drivers/sim/simulated_transducer.hpp"
#include "selfsense/identification/fit_quality.hpp"
#include "selfsense/model_io/model_yaml.hpp"
#include "support/daemon_plant.hpp"
#include "support/shipped_model.hpp"

namespace selfsense::runtime {
namespace {

constexpr double kRate = 10000.0;
constexpr double kTs = 1.0 / kRate;

using test::bench_model;

ControllerConfig bench_control() {
  ControllerConfig c;
  c.position.gains = {2e8, 2.5e11, 0.0};  // E per strain: plant gain about 6e-10 strain per V/m
  c.position.tracking_time = 1e-3;
  c.force.gains = {0.005, 10.0, 0.0};  // E per Pa: about 3 Pa per V/m against the load spring
  c.force.tracking_time = 1e-3;
  c.position_shaper.slew_rate = 0.05;  // strain per s: full stroke in 30 ms
  c.force_shaper.slew_rate = 5e8;      // Pa/s
  c.command_min = 0.0;
  c.command_max = 2e6;
  return c;
}

struct Bench {
  explicit Bench(const plant::PlantConfig& plant_config, const ControllerConfig& control,
                 LoopConfig loop_config = {}, const models::TransducerModel& model = bench_model())
      : driver(plant_config) {
    loop_config.sample_time = kTs;
    std::string why;
    EXPECT_TRUE(driver.configure({kTs}, &why)) << why;
    EXPECT_TRUE(driver.activate(&why)) << why;
    loop = std::make_unique<Loop>(
        loop_config, driver,
        std::make_unique<models::Reconstruction>(model, models::RuntimeOptions{kTs}),
        Controller(control, model.actuator, kTs), nullptr);
  }
  // Submits and runs cycles until the loop answered.
  CommandResult send(LoopCommand c) { return test::send_and_cycle(*loop, next_id, c); }
  void run(double seconds) const {
    const auto n = static_cast<std::int64_t>(seconds * kRate);
    for (std::int64_t i = 0; i < n; ++i)
      loop->cycle(false);
  }
  drivers::SimulatedTransducer driver;
  std::unique_ptr<Loop> loop;
  std::uint64_t next_id{0};
};

void start(Bench& b, ControlMode mode) {
  b.run(0.2);
  ASSERT_EQ(b.send({0, CommandKind::kReset}), CommandResult::kDone);
  ASSERT_EQ(b.send({0, CommandKind::kMode, 0.0, mode}), CommandResult::kDone);
  ASSERT_EQ(b.send({0, CommandKind::kArm}), CommandResult::kDone);
  ASSERT_EQ(b.loop->supervisor().state(), LoopState::kArmed);
}

struct Tracking {
  double truth_nrmse{0.0};  // true S (or T) against the setpoint, share of the setpoint range
  double hat_nrmse{0.0};    // S_hat (or T_hat) against the setpoint
};

// Runs a setpoint trajectory; errors over the samples where `scored` is true.
Tracking track(Bench& b, const std::vector<double>& setpoints, const std::vector<bool>& scored,
               bool force) {
  double sum_truth = 0.0;
  double sum_hat = 0.0;
  std::size_t n = 0;
  for (std::size_t k = 0; k < setpoints.size(); ++k) {
    b.send({0, CommandKind::kSetpoint, setpoints[k]});
    const LoopSample& s = b.loop->local_status().last;
    if (!scored[k]) continue;
    const double truth = force ? s.t_ref : s.s_ref;
    const double hat = force ? s.t_hat : s.s_hat;
    sum_truth += (truth - s.setpoint) * (truth - s.setpoint);
    sum_hat += (hat - s.setpoint) * (hat - s.setpoint);
    ++n;
  }
  for (std::size_t i = 0; i < kFaultCount; ++i) {
    const FaultRecord& r = b.loop->supervisor().record(static_cast<Fault>(i));
    if (r.count > 0 && i > 0) {
      std::printf("fault %s x%llu first at cycle %lld\n",
                  std::string(to_string(static_cast<Fault>(i))).c_str(),
                  static_cast<unsigned long long>(r.count), static_cast<long long>(r.first_cycle));
    }
  }
  const auto [lo, hi] = std::minmax_element(setpoints.begin(), setpoints.end());
  const double range = *hi - *lo;
  return {std::sqrt(sum_truth / static_cast<double>(n)) / range,
          std::sqrt(sum_hat / static_cast<double>(n)) / range};
}

// The position figure's trajectory: a staircase over 80 % of the stroke under the load (strain
// 0.1 .. 0.9 of about 1.25e-3), then three periods of a 1 Hz sine over the same range; scored
// from 0.1 s after each stair and from 0.5 s into the sine.
struct Trajectory {
  std::vector<double> setpoints;
  std::vector<bool> scored;
};

Trajectory position_trajectory() {
  const double lo = 0.15e-3;
  const double hi = 1.1e-3;
  Trajectory out;
  constexpr double kStep = 0.5;  // s per stair
  constexpr double kSettle = 0.1;
  for (const double share : {0.0, 0.5, 1.0, 0.25, 0.75, 0.1}) {
    const double level = lo + (hi - lo) * share;
    for (int k = 0; k < static_cast<int>(kStep * kRate); ++k) {
      out.setpoints.push_back(level);
      out.scored.push_back(k >= static_cast<int>(kSettle * kRate));
    }
  }
  for (int k = 0; k < static_cast<int>(3.0 * kRate); ++k) {  // 1 Hz sine, 3 periods
    const double phase = 2.0 * std::numbers::pi * static_cast<double>(k) * kTs;
    out.setpoints.push_back(0.5 * (lo + hi) - 0.5 * (hi - lo) * std::cos(phase));
    out.scored.push_back(k >= static_cast<int>(0.5 * kRate));
  }
  return out;
}

TEST(Loop, PositionTracksAStaircaseAndASineOnTheSelfSensedStrain) {
  Bench b(test::daemon_plant(kRate), bench_control());
  start(b, ControlMode::kPosition);
  const Trajectory trajectory = position_trajectory();
  const std::vector<double>& sp = trajectory.setpoints;
  const std::vector<bool>& scored = trajectory.scored;
  const Tracking t = track(b, sp, scored, false);
  std::printf("position: true S %.3f %% of range RMS, S_hat %.3f %%\n", 100 * t.truth_nrmse,
              100 * t.hat_nrmse);
  // The loop holds S_hat on the setpoint (measured 0.263 %); the true S is off by that and the
  // model's error under the load spring (measured 0.285 %; the daemon issue's goal is 0.5 %).
  // Deterministic (simulated time): bounded at about 1.3x of the measured figures.
  EXPECT_LT(t.hat_nrmse, 0.0034);
  EXPECT_LT(t.truth_nrmse, 0.0037);
  EXPECT_EQ(b.loop->supervisor().state(), LoopState::kArmed);
}

// Beside the closed loop, the same trajectory driven without feedback: open-loop with the
// inverse hysteresis-creep model as feedforward (the compensator), and the uncompensated linear
// drive (open-loop on a linear model of the same recording: E proportional to the setpoint).
TEST(Loop, PositionAgainstOpenLoopFeedforwardAndTheUncompensatedLinearDrive) {
  const Trajectory trajectory = position_trajectory();
  const models::TransducerModel linear =
      test::identify_daemon_plant(test::daemon_plant(kRate), 40.0, models::Structure::kLinear);
  const auto run = [&](ControlMode mode, const models::TransducerModel& model) {
    Bench b(test::daemon_plant(kRate), bench_control(), {}, model);
    start(b, mode);
    return track(b, trajectory.setpoints, trajectory.scored, false).truth_nrmse;
  };
  const double closed = run(ControlMode::kPosition, bench_model());
  const double feedforward = run(ControlMode::kOpenLoop, bench_model());
  const double uncompensated = run(ControlMode::kOpenLoop, linear);
  std::printf(
      "true S against the setpoint: closed loop on S_hat %.2f %%, open-loop feedforward "
      "%.2f %%, uncompensated linear drive %.2f %% of range RMS\n",
      100 * closed, 100 * feedforward, 100 * uncompensated);
  // Measured 0.28 %, 14.39 %, 16.01 %. Open loop, the compensator removes the hysteresis but not
  // the load spring's push-back (its inverse holds the static load); the loop on S_hat does.
  EXPECT_LT(feedforward, 0.185);
  EXPECT_LT(feedforward, uncompensated);
  EXPECT_LT(closed, 0.05 * feedforward);
}

// A reload's tuning while armed is all or nothing: with an unstable filter section it is
// refused and the loop runs on as before; valid, the narrower command range holds from the
// next cycle, and the loop stays armed.
TEST(Loop, ATuningWhileArmedIsTakenAllOrNothing) {
  Bench b(test::daemon_plant(kRate), bench_control());
  start(b, ControlMode::kPosition);
  b.send({0, CommandKind::kSetpoint, 1.1e-3});
  b.run(0.3);
  ASSERT_GT(b.loop->local_status().last.command, 1.5e6);

  Tuning tuning = tuning_of(bench_control());
  tuning.command_max = 1.2e6;
  tuning.filters[0] = control::BiquadCoefficients{1.0, 0.0, 0.0, 0.0, 1.5};  // |a2| > 1
  tuning.filter_count = 1;
  LoopCommand c{0, CommandKind::kTune};
  c.tuning = tuning;
  EXPECT_EQ(b.send(c), CommandResult::kInvalid);
  b.run(0.01);
  EXPECT_GT(b.loop->local_status().last.command, 1.5e6);

  tuning.filter_count = 0;
  c.tuning = tuning;
  EXPECT_EQ(b.send(c), CommandResult::kDone);
  EXPECT_LE(b.loop->local_status().last.command, 1.2e6);
  b.run(0.1);
  EXPECT_EQ(b.loop->local_status().last.command, 1.2e6);  // saturated, and armed
  EXPECT_EQ(b.loop->supervisor().state(), LoopState::kArmed);
}

// Force steps within reach of 0 .. 2 MV/m against the preload (-3.3 MPa at 0 V/m), 0.6 s each,
// scored from 0.15 s after each step.
Tracking force_steps(Bench& b) {
  std::vector<double> sp;
  std::vector<bool> scored;
  for (const double level : {-5.0e6, -8.0e6, -6.0e6, -9.0e6, -4.5e6}) {
    for (int k = 0; k < static_cast<int>(0.6 * kRate); ++k) {
      sp.push_back(level);
      scored.push_back(k >= static_cast<int>(0.15 * kRate));
    }
  }
  return track(b, sp, scored, true);
}

TEST(Loop, ForceTracksStepsOnTheSelfSensedStress) {
  Bench b(test::daemon_plant(kRate), bench_control());
  start(b, ControlMode::kForce);
  const Tracking t = force_steps(b);
  std::printf("force: true T %.3f %% of range RMS, T_hat %.3f %%\n", 100 * t.truth_nrmse,
              100 * t.hat_nrmse);
  // T_hat on the setpoint (measured 0.340 %); the true T off by that and the model's stress
  // error (measured 0.462 %; the daemon issue's goal is 2 %). Bounds about 1.3x of those.
  EXPECT_LT(t.hat_nrmse, 0.0044);
  EXPECT_LT(t.truth_nrmse, 0.006);
  EXPECT_EQ(b.loop->supervisor().state(), LoopState::kArmed);
}

// The same steps after a position run to 1.2e-3 and back to 0 (another field history, so
// another hysteresis state at each step: the model's error depends on it).
TEST(Loop, ForceTracksStepsAfterAPositionRun) {
  Bench b(test::daemon_plant(kRate), bench_control());
  start(b, ControlMode::kPosition);
  for (const double strain : {1.2e-3, 0.0}) {
    b.send({0, CommandKind::kSetpoint, strain});
    b.run(0.5);
  }
  ASSERT_EQ(b.send({0, CommandKind::kDisarm}), CommandResult::kDone);
  ASSERT_EQ(b.send({0, CommandKind::kMode, 0.0, ControlMode::kForce}), CommandResult::kDone);
  ASSERT_EQ(b.send({0, CommandKind::kArm}), CommandResult::kDone);
  const Tracking t = force_steps(b);
  std::printf("force after position: true T %.3f %% of range RMS, T_hat %.3f %%\n",
              100 * t.truth_nrmse, 100 * t.hat_nrmse);
  // Measured 0.772 % (T_hat 0.339 %); bounds about 1.3x of those.
  EXPECT_LT(t.hat_nrmse, 0.0044);
  EXPECT_LT(t.truth_nrmse, 0.01);
  EXPECT_EQ(b.loop->supervisor().state(), LoopState::kArmed);
}

// Collocated damping on the self-sensed strain (the paper's cantilever application): a mass on
// the stack rings at 300 Hz with 1 % damping after a 300 N, 0.5 ms force impulse. Armed in
// open-loop (the inverse model holds the position) it rings down to 5 % of its first peak in
// about 0.16 s; in damping mode (positive position feedback tuned to the mode) 15x faster.
double ring_down_s(ControlMode mode, const models::TransducerModel& model = bench_model()) {
  ControllerConfig c = bench_control();
  c.damping = {control::DampingController::Law::kPositivePosition,
               8e8,
               300.0,
               0.3,
               std::numeric_limits<double>::infinity(),
               20.0};
  Bench b(test::daemon_plant(kRate, 300.0, 0.01), c, {}, model);
  start(b, mode);
  b.send({0, CommandKind::kSetpoint, 6e-4});
  b.run(0.5);
  const double rest = b.loop->local_status().last.s_ref;
  b.driver.set_external_force(300.0);
  b.run(5 * kTs);
  b.driver.set_external_force(0.0);
  double peak = 0.0;
  double last_large = 0.0;
  for (int i = 0; i < static_cast<int>(2.0 * kRate); ++i) {
    b.loop->cycle(false);
    const double deviation = std::abs(b.loop->local_status().last.s_ref - rest);
    if (i < 100) peak = std::max(peak, deviation);
    if (deviation > 0.05 * peak) last_large = static_cast<double>(i) * kTs;
  }
  EXPECT_EQ(b.loop->supervisor().state(), LoopState::kArmed);
  return last_large;
}

TEST(Loop, DampingShortensTheRingDownTenfold) {
  const double open = ring_down_s(ControlMode::kOpenLoop);
  const double damped = ring_down_s(ControlMode::kDamping);
  std::printf("ring-down to 5 %%: open loop %.4f s, damping %.4f s (%.1fx)\n", open, damped,
              open / damped);
  // Measured 0.159 s and 0.0103 s (15.4x; the goal is 10x): bounded at about 1.3x.
  EXPECT_GT(open, 0.12);  // the undamped mode rings
  EXPECT_LT(open, 0.21);
  EXPECT_GT(damped, 0.0);  // the damped mode rings too: a ring-down, not an impulse never seen
  EXPECT_GT(open / damped, 11.8);
}

// The paper's comparison (20x with a constant permittivity, 60x with eps(E)): the same damping
// run with S_hat from models of the same recording that leave out the dielectric's
// nonlinearity (linear: constant permittivity) or keep only its static curve (permittivity:
// eps(E), no hysteresis), against a hysteresis-creep model of that recording (40 s of ramps;
// the shipped model comes from another recording).
TEST(Loop, DampingWithAConstantPermittivityAgainstEpsOfE) {
  const plant::PlantConfig recorded = test::daemon_plant(kRate);
  const models::TransducerModel linear =
      test::identify_daemon_plant(recorded, 40.0, models::Structure::kLinear);
  const models::TransducerModel eps_of_e =
      test::identify_daemon_plant(recorded, 40.0, models::Structure::kPermittivity);
  const models::TransducerModel hysteresis_creep = test::identify_daemon_plant(recorded, 40.0);
  const double open = ring_down_s(ControlMode::kOpenLoop);
  const double with_linear = ring_down_s(ControlMode::kDamping, linear);
  const double with_eps = ring_down_s(ControlMode::kDamping, eps_of_e);
  const double with_full = ring_down_s(ControlMode::kDamping, hysteresis_creep);
  std::printf(
      "ring-down shortened: constant permittivity %.1fx, eps(E) %.1fx, hysteresis-creep "
      "%.1fx\n",
      open / with_linear, open / with_eps, open / with_full);
  // Measured 12.0x, 8.1x and 14.6x (bounded at about 1.3x below). Not the paper's order: its
  // eps(E) is the static curve, and around an operating point of a hysteretic stack the small
  // ring follows the minor-loop slope, which the hysteresis model tracks after every reversal
  // and the static curve does not.
  EXPECT_GT(with_linear, 0.0);
  EXPECT_GT(with_eps, 0.0);
  EXPECT_GT(with_full, 0.0);
  EXPECT_GT(open / with_linear, 9.2);
  EXPECT_GT(open / with_eps, 6.2);
  EXPECT_GT(open / with_full, 11.2);
  EXPECT_GT(with_linear, 1.1 * with_full);
  EXPECT_GT(with_eps, 1.1 * with_full);
}

// A ramped stop: from the last command straight down to the safe output in the cycles asked for,
// then disarmed; refused unless armed; a fault during it goes to the safe output at once.
TEST(Loop, ARampedStopReachesTheSafeOutputLinearlyThenDisarms) {
  Bench b(test::daemon_plant(kRate), bench_control());
  EXPECT_EQ(b.send({0, CommandKind::kRampDown, 0.01}), CommandResult::kRefusedState);
  start(b, ControlMode::kPosition);
  b.send({0, CommandKind::kSetpoint, 6e-4});
  b.run(0.3);
  const double from = b.loop->local_status().last.command;
  ASSERT_GT(from, 5e5);
  ASSERT_EQ(b.send({0, CommandKind::kRampDown, 100 * kTs}), CommandResult::kDone);
  // send() ran the cycle that took the command: its first ramp cycle.
  int k = 1;
  EXPECT_NEAR(b.loop->local_status().last.command, from * 99.0 / 100.0, 1e-6 * from);
  for (k = 2; k <= 100; ++k) {
    b.loop->cycle(false);
    const LoopSample& s = b.loop->local_status().last;
    EXPECT_NEAR(s.command, from * (100.0 - k) / 100.0, 1e-6 * from) << k;
    EXPECT_EQ(s.state, k < 100 ? LoopState::kArmed : LoopState::kReady) << k;
  }
  b.run(0.01);
  EXPECT_EQ(b.loop->supervisor().state(), LoopState::kReady);
  EXPECT_EQ(b.loop->local_status().last.command, 0.0);

  // Armed again, ramping, then a fault: the safe output in the fault's cycle, latched.
  ASSERT_EQ(b.send({0, CommandKind::kArm}), CommandResult::kDone);
  b.send({0, CommandKind::kSetpoint, 6e-4});
  b.run(0.3);
  ASSERT_EQ(b.send({0, CommandKind::kRampDown, 0.5}), CommandResult::kDone);
  b.run(0.01);
  ASSERT_GT(b.loop->local_status().last.command, 1e5);
  ASSERT_TRUE(b.driver.inject(plant::FaultKind::nan_sample, plant::Channel::d, 0, 3));
  b.loop->cycle(false);
  EXPECT_EQ(b.loop->local_status().last.state, LoopState::kFaulted);
  EXPECT_EQ(b.loop->local_status().last.command, 0.0);
}

// Every fault kind of the simulated transducer reaches the safe output in the cycle it shows
// up in, latches, and a reset afterwards re-arms.
TEST(Loop, EveryFaultReachesTheSafeOutputInItsCycle) {
  struct Case {
    plant::FaultKind kind;
    plant::Channel channel;
    Fault expected;
  };
  const Case cases[] = {
      {plant::FaultKind::nan_sample, plant::Channel::d, Fault::kDriverError},
      {plant::FaultKind::out_of_range, plant::Channel::e, Fault::kDriverError},
      {plant::FaultKind::stuck_adc, plant::Channel::d, Fault::kStaleSample},
      {plant::FaultKind::missed_data_ready, plant::Channel::both, Fault::kStaleSample},
      {plant::FaultKind::amplifier_fault, plant::Channel::both, Fault::kAmplifierFault},
      {plant::FaultKind::sensor_disconnect, plant::Channel::d, Fault::kDriverError},
  };
  LoopConfig lc;
  lc.safe_value = 0.0;
  Bench b(test::daemon_plant(kRate), bench_control(), lc);
  for (const Case& c : cases) {
    start(b, ControlMode::kPosition);
    b.send({0, CommandKind::kSetpoint, 0.6e-3});
    b.run(0.3);
    ASSERT_EQ(b.loop->supervisor().state(), LoopState::kArmed);
    ASSERT_GT(b.loop->local_status().last.command, 1e5);
    ASSERT_TRUE(b.driver.inject(c.kind, c.channel, 1, 5));
    b.loop->cycle(false);
    EXPECT_EQ(b.loop->local_status().last.state, LoopState::kArmed) << plant::to_string(c.kind);
    b.loop->cycle(false);  // the faulty sample arrives in this cycle
    const LoopSample& s = b.loop->local_status().last;
    EXPECT_EQ(s.state, LoopState::kFaulted) << plant::to_string(c.kind);
    EXPECT_EQ(s.command, 0.0) << plant::to_string(c.kind);
    EXPECT_EQ(b.driver.command(), 0.0) << plant::to_string(c.kind);
    EXPECT_NE(s.faults & bit(c.expected), 0U) << plant::to_string(c.kind);
    b.run(0.01);  // the fault is over; the state stays latched
    EXPECT_EQ(b.loop->supervisor().state(), LoopState::kFaulted);
    EXPECT_EQ(b.loop->local_status().last.command, 0.0);
  }
}

TEST(Loop, ArmingIsRefusedWhileFaultedAndResetIsRefusedWhileTheCauseLasts) {
  Bench b(test::daemon_plant(kRate), bench_control());
  b.run(0.05);
  EXPECT_EQ(b.send({0, CommandKind::kArm}), CommandResult::kRefusedState);
  ASSERT_TRUE(b.driver.inject(plant::FaultKind::nan_sample, plant::Channel::d, 0, 100000));
  b.run(0.01);
  EXPECT_EQ(b.send({0, CommandKind::kReset}), CommandResult::kRefusedCause);
  EXPECT_EQ(b.loop->supervisor().state(), LoopState::kFaulted);
}

// A model reload: refused while armed (the new estimate would step the actuator) and the
// objects handed back; taken while disarmed, the feedforward with it, and the loop tracks again.
TEST(Loop, AModelIsSwappedOnlyWhileDisarmedWithItsFeedforward) {
  ControllerConfig control = bench_control();
  Bench b(test::daemon_plant(kRate), control);
  start(b, ControlMode::kPosition);
  const auto offer = [&] {
    LoopCommand c{0, CommandKind::kSwapModel};
    c.model = new models::Reconstruction(bench_model(), models::RuntimeOptions{kTs});
    c.feedforward = new Feedforward(make_feedforward(control, bench_model().actuator, kTs));
    return b.send(c);
  };
  const auto collect = [&] {
    std::size_t n = 0;
    Retired r;
    while (b.loop->take_retired(r)) {
      n += (r.model != nullptr ? 1U : 0U) + (r.feedforward != nullptr ? 1U : 0U);
      delete r.model;
      delete r.feedforward;
    }
    return n;
  };
  EXPECT_EQ(offer(), CommandResult::kRefusedState);
  EXPECT_EQ(collect(), 2U);  // the offered model and feedforward, untouched
  EXPECT_EQ(b.loop->local_status().model_swaps, 0U);

  ASSERT_EQ(b.send({0, CommandKind::kDisarm}), CommandResult::kDone);
  EXPECT_EQ(offer(), CommandResult::kDone);
  EXPECT_EQ(collect(), 2U);  // the replaced model and feedforward
  EXPECT_EQ(b.loop->local_status().model_swaps, 1U);
  EXPECT_TRUE(b.loop->controller().has_feedforward());

  ASSERT_EQ(b.send({0, CommandKind::kArm}), CommandResult::kDone);
  b.send({0, CommandKind::kSetpoint, 8e-4});
  b.run(0.3);
  const LoopSample& s = b.loop->local_status().last;
  EXPECT_EQ(b.loop->supervisor().state(), LoopState::kArmed);
  EXPECT_NEAR(s.s_hat, 8e-4, 2e-5);  // 2 % of the setpoint: tracking on the new model
}

// The feedforward with the stack's drift (Controller::set_feedforward_scales, fed by the loop
// from a measured temperature): the inverse sees the target divided by the response scale, so
// the command for strain S at scale 1.1 is the unscaled command for y0 + (S - y0) / 1.1; an
// insane scale is taken as 1.
TEST(Controller, TheFeedforwardDividesItsTargetByTheDriftedResponse) {
  const models::TransducerModel& model = bench_model();
  ControllerConfig c = bench_control();
  c.mode = ControlMode::kOpenLoop;
  c.position_shaper.slew_rate = 0.0;
  const double y0 = model.actuator->offset;
  const auto command = [&](double strain, double response_scale) {
    Controller ctl(c, model.actuator, kTs);
    ctl.arm(strain, 0.0, 0.0);
    ctl.set_feedforward_scales(response_scale, 1.0);
    double u = 0.0;
    for (int k = 0; k < 10; ++k)
      u = ctl.step(strain, strain, 0.0);
    return u;
  };
  const double strain = 6e-4;
  const double scaled = command(strain, 1.1);
  EXPECT_NEAR(scaled, command(y0 + (strain - y0) / 1.1, 1.0), 1e-6 * scaled);
  EXPECT_LT(scaled, command(strain, 1.0));
  EXPECT_EQ(command(strain, 3.0), command(strain, 1.0));
  EXPECT_EQ(command(strain, std::nan("")), command(strain, 1.0));
}

TEST(Loop, OverrunPolicyAndWatchdogFault) {
  LoopConfig lc;
  lc.overrun = {3, 5, 100};
  lc.watchdog_s = 0.05;
  Bench b(test::daemon_plant(kRate), bench_control(), lc);
  start(b, ControlMode::kPosition);
  b.loop->cycle(true);
  b.loop->cycle(true);
  b.loop->cycle(false);
  EXPECT_EQ(b.loop->supervisor().state(), LoopState::kArmed);
  b.loop->cycle(true);
  b.loop->cycle(true);
  b.loop->cycle(true);  // three in a row
  EXPECT_EQ(b.loop->supervisor().state(), LoopState::kFaulted);
  EXPECT_NE(b.loop->supervisor().latched() & bit(Fault::kOverrun), 0U);

  ASSERT_EQ(b.send({0, CommandKind::kReset}), CommandResult::kDone);
  ASSERT_EQ(b.send({0, CommandKind::kArm}), CommandResult::kDone);
  b.run(0.04);
  EXPECT_EQ(b.loop->supervisor().state(), LoopState::kArmed);
  b.run(0.02);  // no setpoint for longer than the watchdog
  EXPECT_NE(b.loop->supervisor().latched() & bit(Fault::kWatchdog), 0U);
  EXPECT_EQ(b.loop->local_status().last.command, 0.0);
}

// One stall is as long as many late cycles: a cycle late by k missed periods counts k + 1
// overruns in a row (a 100 ms stall used to count as one; found by the soak test).
TEST(Loop, AStallCountsEveryDeadlineItMissed) {
  LoopConfig lc;
  lc.overrun = {200, 64, 64};
  Bench b(test::daemon_plant(kRate), bench_control(), lc);
  start(b, ControlMode::kPosition);
  b.loop->cycle(true, 150);  // 151 in a row
  b.loop->cycle(false);
  EXPECT_EQ(b.loop->supervisor().state(), LoopState::kArmed);
  b.loop->cycle(true, 198);
  EXPECT_EQ(b.loop->supervisor().state(), LoopState::kArmed);
  b.loop->cycle(true);  // 200 in a row
  EXPECT_EQ(b.loop->supervisor().state(), LoopState::kFaulted);
  EXPECT_NE(b.loop->supervisor().latched() & bit(Fault::kOverrun), 0U);
  EXPECT_EQ(b.loop->local_status().last.command, 0.0);
}

// within_count 0 leaves only the stall criterion (config/sim.yaml on a shared machine): long
// runs of late cycles do not fault, a stall of `consecutive` missed deadlines still does.
TEST(Loop, WithinCountZeroFaultsOnlyOnAStall) {
  LoopConfig lc;
  lc.overrun = {2000, 0, 64};
  std::string why;
  ASSERT_TRUE(lc.overrun.is_valid(&why)) << why;
  Bench b(test::daemon_plant(kRate), bench_control(), lc);
  start(b, ControlMode::kPosition);
  for (int k = 0; k < 500; ++k) {
    b.loop->cycle(true);  // late, one overrun each
    b.loop->cycle(false);
  }
  for (int k = 0; k < 900; ++k)
    b.loop->cycle(true);  // 900 late cycles in a row
  b.loop->cycle(false);
  EXPECT_EQ(b.loop->supervisor().state(), LoopState::kArmed);
  b.loop->cycle(true, 1998);  // 1999 in a row
  EXPECT_EQ(b.loop->supervisor().state(), LoopState::kArmed);
  b.loop->cycle(true);  // 2000 in a row
  EXPECT_EQ(b.loop->supervisor().state(), LoopState::kFaulted);
  EXPECT_NE(b.loop->supervisor().latched() & bit(Fault::kOverrun), 0U);
  EXPECT_FALSE((OverrunPolicy{2000, 65, 100}.is_valid(&why)));
  EXPECT_EQ(why, "safety.overrun.within_count: 65 must be within [0, 64]");
}

// A wave that ended or was stopped after playing longer than the watchdog used to fault in the
// next cycle (the watchdog counted from the wave's request); found by the soak test (tests/soak).
TEST(Loop, TheWatchdogCountsTheHoldFromTheEndOfAWave) {
  LoopConfig lc;
  lc.watchdog_s = 0.05;
  Bench b(test::daemon_plant(kRate), bench_control(), lc);
  start(b, ControlMode::kPosition);
  control::WaveGenerator::Config stopped{};
  stopped.amplitude = 2e-4;
  stopped.offset = 5e-4;
  stopped.frequency = 5.0;
  LoopCommand wave{0, CommandKind::kWave};
  wave.wave = new control::WaveGenerator(stopped, kTs);  // NOLINT(cppcoreguidelines-owning-memory)
  ASSERT_EQ(b.send(wave), CommandResult::kDone);
  b.run(0.2);  // four watchdog periods of wave
  ASSERT_EQ(b.send({0, CommandKind::kStopWave}), CommandResult::kDone);
  b.run(0.04);
  EXPECT_EQ(b.loop->supervisor().state(), LoopState::kArmed) << "faulted on the wave's stop";
  b.run(0.02);
  EXPECT_NE(b.loop->supervisor().latched() & bit(Fault::kWatchdog), 0U);

  ASSERT_EQ(b.send({0, CommandKind::kReset}), CommandResult::kDone);
  ASSERT_EQ(b.send({0, CommandKind::kArm}), CommandResult::kDone);
  control::WaveGenerator::Config finite = stopped;
  finite.repeats = 1;                                   // ends by itself after 0.2 s
  wave.wave = new control::WaveGenerator(finite, kTs);  // NOLINT(cppcoreguidelines-owning-memory)
  ASSERT_EQ(b.send(wave), CommandResult::kDone);
  Retired first;  // the stopped wave, handed back when the second replaced it
  ASSERT_TRUE(b.loop->take_retired(first));
  delete first.wave;  // NOLINT(cppcoreguidelines-owning-memory)
  b.run(0.2 + 0.04);
  EXPECT_EQ(b.loop->supervisor().state(), LoopState::kArmed) << "faulted at the wave's end";
  b.run(0.02);
  EXPECT_NE(b.loop->supervisor().latched() & bit(Fault::kWatchdog), 0U);
}

}  // namespace
}  // namespace selfsense::runtime
