#include "selfsense/runtime/loop.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "selfsense/base/check.hpp"

namespace selfsense::runtime {
namespace {

constexpr std::size_t kRetiredCapacity = 64;
constexpr int kCommandsPerCycle = 8;  // bounds the cycle's work; the rest waits a cycle

Fault fault_of(DriverStatus s) noexcept {
  switch (s) {
    case DriverStatus::kTimeout:
    case DriverStatus::kDisconnected:
      return Fault::kDriverTimeout;
    case DriverStatus::kStale:
      return Fault::kStaleSample;
    case DriverStatus::kDeviceFault:
      return Fault::kAmplifierFault;
    case DriverStatus::kBadData:
    case DriverStatus::kNotActive:
    case DriverStatus::kOk:
      break;
  }
  return Fault::kDriverError;
}

Fault fault_of(models::SampleStatus s) noexcept {
  switch (s) {
    case models::SampleStatus::kInputNotFinite:
      return Fault::kInputNotFinite;
    case models::SampleStatus::kInputOutOfRange:
      return Fault::kInputOutOfRange;
    default:
      return Fault::kReconstruction;
  }
}

}  // namespace

bool LoopConfig::is_valid(std::string* why) const {
  namespace check = base::check;
  if (!(sample_time >= 1.0 / 100000.0 && sample_time <= 1.0 / 100.0)) {
    return check::fail("loop.rate_hz", "must be within [100, 100000]", why);
  }
  if (!check::finite("safety.safe_value", safe_value, why)) return false;
  if (!(strain_min < strain_max))
    return check::fail("safety.strain_range", "min must be < max", why);
  if (!(stress_min < stress_max))
    return check::fail("safety.stress_range", "min must be < max", why);
  if (!check::non_negative("safety.watchdog_s", watchdog_s, why)) return false;
  if (!check::require(status_period >= 1, "loop.status_period", status_period, "must be >= 1",
                      why) ||
      !check::require(command_capacity >= 2, "loop.command_capacity", command_capacity,
                      "must be >= 2", why)) {
    return false;
  }
  if (health_enabled &&
      (!health.is_valid("health.", why) || !health_bands.is_valid("health.", why))) {
    return false;
  }
  return overrun.is_valid(why);
}

Loop::Loop(const LoopConfig& config, Driver& driver, std::unique_ptr<models::Reconstruction> model,
           const Controller& controller, SampleSink* sink)
    : Loop(config, driver, std::move(model), nullptr, controller, sink) {
  if (!model_) throw std::invalid_argument("loop: needs a model");
}

Loop::Loop(const LoopConfig& config, Driver& driver,
           std::unique_ptr<adaptation::AdaptedReconstruction> model, const Controller& controller,
           SampleSink* sink)
    : Loop(config, driver, nullptr, std::move(model), controller, sink) {
  if (!adapted_) throw std::invalid_argument("loop: needs a model");
}

Loop::Loop(const LoopConfig& config, Driver& driver, std::unique_ptr<models::Reconstruction> model,
           std::unique_ptr<adaptation::AdaptedReconstruction> adapted, const Controller& controller,
           SampleSink* sink)
    : config_(config),
      driver_(&driver),
      model_(std::move(model)),
      adapted_(std::move(adapted)),
      controller_(controller),
      sink_(sink),
      supervisor_(config.overrun),
      commands_(config.command_capacity),
      answers_(config.command_capacity),
      retired_(kRetiredCapacity) {
  std::string why;
  if (!config.is_valid(&why)) throw std::invalid_argument(why);
  command_ = safe_command();
  status_.mode = controller_.mode();
  if (config_.health_enabled) {
    health_.emplace(config_.health, config_.sample_time);
    alarms_.emplace(config_.health_bands);
    status_.health.enabled = true;
    status_.health.fault = config_.health_bands.fault;
    status_.health.raised_at_s.fill(-1.0);
  }
  // The first snapshot, from the configuration: until the loop's first status period, a
  // status request sees the adaptation and health that are configured (figures not yet
  // measured), not a default that says they are off.
  publish_adaptation();
  publish_health();
  published_.publish(status_);
}

// Whatever the control thread did not collect is freed here (never on the loop thread).
Loop::~Loop() {
  Retired r;
  while (retired_.try_pop(r)) {
    delete r.wave;         // NOLINT(cppcoreguidelines-owning-memory): handed back by handle()
    delete r.model;        // NOLINT(cppcoreguidelines-owning-memory)
    delete r.feedforward;  // NOLINT(cppcoreguidelines-owning-memory)
  }
}

double Loop::safe_command() const noexcept {
  return config_.safe_output == SafeOutput::kHold ? command_ : config_.safe_value;
}

void Loop::answer(const LoopCommand& c, CommandResult r) noexcept {
  static_cast<void>(answers_.try_push({c.id, r, supervisor_.state()}));
}

void Loop::handle(const LoopCommand& c) noexcept {
  ++status_.commands;
  switch (c.kind) {
    case CommandKind::kArm:
      if (!estimate_valid_ || !supervisor_.arm()) return answer(c, CommandResult::kRefusedState);
      controller_.arm(s_hat_, t_hat_, command_);
      hold_setpoint_ = controller_.mode() == ControlMode::kForce ? t_hat_ : s_hat_;
      last_feed_ = cycle_;
      return answer(c, CommandResult::kDone);
    case CommandKind::kDisarm:
      ramp_left_ = 0;
      return answer(c, supervisor_.disarm() ? CommandResult::kDone : CommandResult::kRefusedState);
    case CommandKind::kSaveState: {
      if (!c.health_state.empty() && c.health_state.size() != health_state_size()) {
        return answer(c, CommandResult::kInvalid);
      }
      const bool saved = c.state != nullptr &&
                         (adapted_ ? adapted_->save_state(*c.state) : model_->save_state(*c.state));
      if (saved && !c.health_state.empty()) {
        health_->save_state(c.health_state.first(adaptation::HealthEstimator::kStateSize));
        alarms_->save_state(c.health_state.subspan(adaptation::HealthEstimator::kStateSize));
      }
      return answer(c, saved ? CommandResult::kDone : CommandResult::kInvalid);
    }
    case CommandKind::kAdapt:
      if (!adapted_) return answer(c, CommandResult::kInvalid);
      adapted_->set_frozen(c.value != 0.0);
      publish_adaptation();
      return answer(c, CommandResult::kDone);
    case CommandKind::kRampDown: {
      if (!supervisor_.armed()) return answer(c, CommandResult::kRefusedState);
      if (!(c.value >= 0.0) || !std::isfinite(c.value)) return answer(c, CommandResult::kInvalid);
      ramp_from_ = command_;
      ramp_cycles_ = std::max<std::int64_t>(1, std::llround(c.value / config_.sample_time));
      ramp_left_ = ramp_cycles_;
      return answer(c, CommandResult::kDone);
    }
    case CommandKind::kReset:
      return answer(c, reset());
    case CommandKind::kSetpoint:
      hold_setpoint_ = c.value;
      wave_running_ = false;
      last_feed_ = cycle_;
      return answer(c, CommandResult::kDone);
    case CommandKind::kHeartbeat:
      last_feed_ = cycle_;
      return answer(c, CommandResult::kDone);
    case CommandKind::kMode:
      // Bumpless while armed too: the new mode starts at the measured state.
      controller_.set_mode(c.mode, s_hat_, t_hat_, command_);
      hold_setpoint_ = c.mode == ControlMode::kForce ? t_hat_ : s_hat_;
      wave_running_ = false;
      return answer(c, CommandResult::kDone);
    case CommandKind::kWave:
      if (wave_) static_cast<void>(retired_.try_push({wave_.release(), nullptr, nullptr}));
      wave_.reset(c.wave);
      wave_running_ = wave_ != nullptr;
      last_feed_ = cycle_;
      return answer(c, CommandResult::kDone);
    case CommandKind::kStopWave:
      if (wave_running_) {
        hold_setpoint_ = last_wave_value_;
        last_feed_ = cycle_;  // the watchdog counts the hold from here, not from the wave's start
      }
      wave_running_ = false;
      return answer(c, CommandResult::kDone);
    case CommandKind::kTune:
      return answer(c, controller_.tune(c.tuning) ? CommandResult::kDone : CommandResult::kInvalid);
    case CommandKind::kSwapModel:
      // Not under a closed loop: the new model's estimate may differ from the old one's, and
      // a step of the estimate would be a step of the actuator. What is refused is handed back.
      // Nor under adaptation: the learned drift is relative to the running model.
      if (c.model == nullptr || adapted_ || supervisor_.state() == LoopState::kArmed) {
        static_cast<void>(retired_.try_push({nullptr, c.model, c.feedforward}));
        return answer(c, c.model == nullptr || adapted_ ? CommandResult::kInvalid
                                                        : CommandResult::kRefusedState);
      }
      c.model->adopt_state(*model_);
      if (c.feedforward != nullptr) controller_.swap_feedforward(*c.feedforward);
      static_cast<void>(retired_.try_push({nullptr, model_.release(), c.feedforward}));
      model_.reset(c.model);
      ++status_.model_swaps;
      return answer(c, CommandResult::kDone);
  }
}

// A refused reset changes nothing: the checks come before anything is cleared.
CommandResult Loop::reset() noexcept {
  const std::uint32_t latched = alarms_ ? alarms_->latched() : 0U;
  const std::uint32_t clearable = alarms_ ? latched & ~alarms_->active() : 0U;
  if (supervisor_.state() == LoopState::kFaulted) {
    if (active_causes_ != 0) return CommandResult::kRefusedCause;
    supervisor_.reset();
  } else if (clearable == 0U) {
    // Not faulted: only warnings to clear. None latched: nothing to reset; all still beyond
    // their bands: their cause lasts.
    return latched == 0U ? CommandResult::kRefusedState : CommandResult::kRefusedCause;
  }
  if (alarms_) static_cast<void>(alarms_->reset());
  return CommandResult::kDone;
}

models::Reconstruction::Estimate Loop::estimate(double e, double d) noexcept {
  predicted_d_ = adaptation::HealthEstimator::kNoPrediction;
  if (!adapted_) return model_->step(e, d);
  // Learning only from a sample nothing else in this cycle found wrong.
  const adaptation::AdaptedReconstruction::Estimate a = adapted_->step(e, d, active_causes_ == 0);
  if (a.status == models::SampleStatus::kOk) predicted_d_ = a.predicted_sensed;
  return {a.stress, a.strain, a.status};
}

void Loop::publish_adaptation() noexcept {
  if (!adapted_) return;
  const adaptation::Drift drift = adapted_->drift();
  status_.adaptation = {true,
                        adapted_->estimator().frozen(),
                        drift.permittivity,
                        drift.loop,
                        drift.temperature_degc,
                        static_cast<std::uint64_t>(adapted_->estimator().updates())};
}

void Loop::follow_health(bool accepted, double e, double d) noexcept {
  if (!health_) return;
  static_cast<void>(health_->step(e, d, predicted_d_, accepted));
  if (cycle_ % config_.status_period == 0) {
    const bool has_temperature = adapted_ != nullptr;
    const double temperature = has_temperature ? adapted_->drift().temperature_degc : 0.0;
    static_cast<void>(
        alarms_->evaluate(health_->figures(), has_temperature, temperature, health_->time_s()));
  }
  if (config_.health_bands.fault && alarms_->active() != 0U) {
    active_causes_ |= bit(Fault::kHealth);
    supervisor_.report(Fault::kHealth, cycle_);
  }
}

bool Loop::restore_health_state(std::span<const double> in) noexcept {
  if (!health_ || in.size() != kHealthStateSize) return false;
  health_->restore_state(in.first(adaptation::HealthEstimator::kStateSize));
  alarms_->restore_state(in.subspan(adaptation::HealthEstimator::kStateSize));
  publish_health();
  published_.publish(status_);
  return true;
}

void Loop::publish_health() noexcept {
  if (!health_) return;
  HealthStatus& h = status_.health;
  h.figures = health_->figures();
  h.active = alarms_->active();
  h.latched = alarms_->latched();
  for (std::size_t i = 0; i < adaptation::kHealthAlarmCount; ++i)
    h.raised_at_s[i] = alarms_->raised_at_s(static_cast<adaptation::HealthAlarm>(i));
}

double Loop::setpoint() noexcept {
  if (wave_running_ && wave_) {
    const double v = wave_->step();
    last_wave_value_ = v;
    if (wave_->done()) {
      hold_setpoint_ = v;
      wave_running_ = false;
      last_feed_ = cycle_;  // as a stop: the hold starts now
    }
    return v;
  }
  return hold_setpoint_;
}

void Loop::cycle(bool overrun, std::int64_t missed) noexcept {
  ++cycle_;
  for (int i = 0; i < kCommandsPerCycle; ++i) {
    LoopCommand c;
    if (!commands_.try_pop(c)) break;
    handle(c);
  }
  active_causes_ = 0;
  const auto cause = [this](Fault f) {
    active_causes_ |= bit(f);
    supervisor_.report(f, cycle_);
  };

  // read
  InputSample in;
  const DriverStatus read = driver_->read(in);
  if (read != DriverStatus::kOk) cause(fault_of(read));

  // estimate
  LoopSample sample;
  sample.cycle = cycle_;
  sample.t = static_cast<double>(cycle_) * config_.sample_time;
  sample.e = in.e;
  sample.d = in.d;
  sample.s_ref = in.s_ref;
  sample.t_ref = in.t_ref;
  sample.temp_ref = in.temp_ref;
  sample.driver_status = in.device_status;
  bool temperature_measured = false;
  if (adapted_ && config_.adaptation_temperature) {
    temperature_measured = read == DriverStatus::kOk && std::isfinite(in.temp_ref);
    if (temperature_measured) {
      adapted_->set_temperature(in.temp_ref);
    } else {
      adapted_->clear_temperature();
    }
  }
  if (read == DriverStatus::kOk) {
    const models::Reconstruction::Estimate est = estimate(in.e, in.d);
    sample.estimate_status = static_cast<std::uint8_t>(est.status);
    ++status_.estimate_status[static_cast<std::size_t>(est.status)];
    if (est.status != models::SampleStatus::kOk) {
      cause(fault_of(est.status));
    } else {
      const bool strain_ok = !std::isfinite(est.strain) ||
                             (est.strain >= config_.strain_min && est.strain <= config_.strain_max);
      const bool stress_ok = est.stress >= config_.stress_min && est.stress <= config_.stress_max;
      if (!strain_ok || !stress_ok) {
        cause(Fault::kEstimateOutOfRange);
        if (adapted_) adapted_->skip();
      }
      s_hat_ = std::isfinite(est.strain) ? est.strain : 0.0;
      t_hat_ = est.stress;
      estimate_valid_ = true;
    }
    sample.t_hat = est.stress;
    sample.s_hat = est.strain;
  } else {
    predicted_d_ = adaptation::HealthEstimator::kNoPrediction;
    if (adapted_) adapted_->skip();
  }
  // The feedforward's inverse follows the stack as adapted in this cycle: at a measured
  // temperature through the model's fitted coefficients, and from the drift estimated from E
  // and D when configured (docs/adaptation.md, "The feedforward with the adapted parameters").
  const bool measured_ff = temperature_measured && adapted_->has_temperature_coefficients();
  if (adapted_ && (measured_ff || config_.adaptation_feedforward_estimate)) {
    const adaptation::AdaptedReconstruction::FeedforwardScales g = adapted_->feedforward_scales();
    controller_.set_feedforward_scales(g.response, g.compliance);
  } else {
    controller_.set_feedforward_scales(1.0, 1.0);
  }
  follow_health(read == DriverStatus::kOk && active_causes_ == 0, in.e, in.d);
  supervisor_.note_cycle(overrun, cycle_, missed);
  if (config_.watchdog_s > 0.0 && supervisor_.armed() && !wave_running_ &&
      static_cast<double>(cycle_ - last_feed_) * config_.sample_time > config_.watchdog_s) {
    cause(Fault::kWatchdog);
  }

  // control: the safe output unless armed and nothing went wrong in this cycle
  const double r = setpoint();
  if (!supervisor_.armed()) ramp_left_ = 0;  // a fault or disarm ends a ramp at once
  if (ramp_left_ > 0) {
    const double safe = safe_command();
    --ramp_left_;
    command_ = safe + (ramp_from_ - safe) * static_cast<double>(ramp_left_) /
                          static_cast<double>(ramp_cycles_);
    if (ramp_left_ == 0) static_cast<void>(supervisor_.disarm());
  } else if (supervisor_.armed()) {
    command_ = controller_.step(r, s_hat_, t_hat_);
  } else {
    command_ = safe_command();
  }
  const DriverStatus wrote = driver_->write(OutputCommand{command_});
  if (wrote != DriverStatus::kOk) supervisor_.report(fault_of(wrote), cycle_);

  // record
  sample.setpoint = r;
  sample.command = command_;
  sample.state = supervisor_.state();
  sample.mode = controller_.mode();
  sample.faults = supervisor_.latched();
  if (adapted_) sample.temp_equivalent = adapted_->drift().temperature_degc;
  if (sink_ != nullptr && !sink_->push(sample)) ++status_.samples_dropped;

  status_.cycle = cycle_;
  status_.last = sample;
  status_.state = supervisor_.state();
  status_.mode = controller_.mode();
  status_.faults = supervisor_.latched();
  status_.saturations = controller_.saturations();
  status_.wave_running = wave_running_;
  if (cycle_ % config_.status_period == 0) {
    for (std::size_t i = 0; i < kFaultCount; ++i)
      status_.fault_records[i] = supervisor_.record(static_cast<Fault>(i));
    status_.driver = driver_->counters();
    publish_adaptation();
    publish_health();
    published_.publish(status_);
  }
}

void Loop::set_timing(const StatusSnapshot& timing) noexcept {
  status_.overruns = timing.overruns;
  status_.missed_periods = timing.missed_periods;
  status_.wake_latency_p50_ns = timing.wake_latency_p50_ns;
  status_.wake_latency_p99_ns = timing.wake_latency_p99_ns;
  status_.wake_latency_max_ns = timing.wake_latency_max_ns;
  status_.cycle_time_p50_ns = timing.cycle_time_p50_ns;
  status_.cycle_time_p99_ns = timing.cycle_time_p99_ns;
  status_.cycle_time_max_ns = timing.cycle_time_max_ns;
  status_.last_overrun_cycle = timing.last_overrun_cycle;
}

}  // namespace selfsense::runtime
