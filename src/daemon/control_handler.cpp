#include "selfsense/daemon/control_handler.hpp"

#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <variant>

#include "selfsense/control/wave_generator.hpp"
#include "selfsense/daemon/daemon.hpp"
#include "selfsense/daemon/health_report.hpp"
#include "selfsense/runtime/supervisor.hpp"

namespace selfsense::daemon {
namespace {

constexpr std::chrono::milliseconds kAnswerTimeout{500};

nlohmann::json number_or_null(double x) {
  return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr);
}

// 64-bit hash as 16 hexadecimal digits (a JSON number would lose bits).
std::string hex(std::uint64_t value) {
  std::array<char, 17> text{};
  static_cast<void>(
      std::snprintf(text.data(), text.size(), "%016llx", static_cast<unsigned long long>(value)));
  return {text.data()};
}

// The online drift estimate (status `adaptation`, `ctl adapt show`).
nlohmann::json adaptation_json(const runtime::AdaptationStatus& a) {
  if (!a.enabled) return {{"enabled", false}};
  return {{"enabled", true},
          {"frozen", a.frozen},
          {"permittivity_change", a.permittivity},
          {"loop_change", a.loop},
          {"temperature_degc", a.temperature_degc},
          {"updates", a.updates}};
}

}  // namespace

RequestLimits ControlHandler::limits() {
  const DaemonConfig& c = daemon_->config();
  RequestLimits l;
  l.mode = daemon_->status().mode;
  const SetpointRange strain{c.safety.setpoint_strain.min, c.safety.setpoint_strain.max};
  const SetpointRange stress{c.safety.setpoint_stress_pa.min, c.safety.setpoint_stress_pa.max};
  l.setpoint[static_cast<std::size_t>(runtime::ControlMode::kPosition)] = strain;
  l.setpoint[static_cast<std::size_t>(runtime::ControlMode::kOpenLoop)] = strain;
  l.setpoint[static_cast<std::size_t>(runtime::ControlMode::kDamping)] = strain;
  l.setpoint[static_cast<std::size_t>(runtime::ControlMode::kForce)] = stress;
  l.sample_time = c.sample_time();
  l.max_frequency_hz = 0.4 * c.loop.rate_hz;
  return l;
}

nlohmann::json ControlHandler::send(runtime::LoopCommand command, const char* what,
                                    bool* submitted) {
  const auto answer = daemon_->command(command, kAnswerTimeout, submitted);
  if (!answer) return error_reply(std::string(what) + ": the loop did not answer in time");
  switch (answer->result) {
    case runtime::CommandResult::kDone:
      return ok_reply({{"state", runtime::to_string(answer->state)}});
    case runtime::CommandResult::kRefusedState:
      return error_reply(std::string(what) + ": not allowed while " +
                         runtime::to_string(answer->state) +
                         (answer->state == runtime::LoopState::kFaulted ? " (reset first)" : ""));
    case runtime::CommandResult::kRefusedCause:
      // Not faulted: a reset had only health warnings to clear, all still beyond their bands.
      return error_reply(std::string(what) + (answer->state == runtime::LoopState::kFaulted
                                                  ? ": a fault's cause is still present"
                                                  : ": a health warning is still beyond its band"));
    case runtime::CommandResult::kInvalid:
      break;
  }
  return error_reply(std::string(what) + ": refused by the control law");
}

nlohmann::json ControlHandler::status() {
  const runtime::StatusSnapshot s = daemon_->status();
  nlohmann::json faults = nlohmann::json::array();
  nlohmann::json fault_details = nlohmann::json::object();
  const double rate_hz = daemon_->config().loop.rate_hz;
  const runtime::OverrunPolicy& overrun = daemon_->config().safety.overrun;
  const auto cause = [&overrun](runtime::Fault f) {
    std::string text(runtime::cause_of(f));
    if (f == runtime::Fault::kOverrun) {
      text += " (" + std::to_string(overrun.consecutive) + " in a row";
      if (overrun.within_count > 0) {
        text += ", or " + std::to_string(overrun.within_count) + " within " +
                std::to_string(overrun.window) + " cycles";
      }
      text += ")";
    }
    return text;
  };
  for (std::size_t i = 0; i < runtime::kFaultCount; ++i) {
    const auto f = static_cast<runtime::Fault>(i);
    const runtime::FaultRecord& r = s.fault_records[i];
    if ((s.faults & runtime::bit(f)) != 0U) faults.push_back(std::string(runtime::to_string(f)));
    if (r.count > 0) {
      // The loop's time of those cycles (a recording's t), and what the fault means.
      fault_details[std::string(runtime::to_string(f))] = {
          {"count", r.count},
          {"first_cycle", r.first_cycle},
          {"last_cycle", r.last_cycle},
          {"first_s", static_cast<double>(r.first_cycle) / rate_hz},
          {"last_s", static_cast<double>(r.last_cycle) / rate_hz},
          {"cause", cause(f)}};
    }
  }
  const RecorderCounters rec = daemon_->recorder().counters();
  nlohmann::json counters = {
      {"cycles", s.cycle},
      {"commands", s.commands},
      {"saturations", s.saturations},
      {"samples_dropped", rec.samples_dropped},
      {"rows_lost", rec.rows_lost},
      {"write_errors", rec.write_errors},
      {"flight_dumps", rec.flight_dumps},
      {"rows_written", rec.rows_written},
      {"files", rec.files},
      {"model_swaps", s.model_swaps},
      {"driver_reads", s.driver.reads},
      {"driver_errors", s.driver.errors},
      {"driver_timeouts", s.driver.timeouts},
      {"driver_stale", s.driver.stale},
      {"driver_bad_data", s.driver.bad_data},
      {"driver_device_faults", s.driver.device_faults},
      {"driver_retries", s.driver.retries},
      {"driver_reconnects", s.driver.reconnects},
      {"driver_writes", s.driver.writes},
      {"driver_crc_errors", s.driver.crc_errors},
  };
  // The driver's own counters under their names (docs/drivers/*.md), e.g. spi's no_new_data.
  nlohmann::json driver_events = nlohmann::json::object();
  for (const runtime::NamedCount& e : s.driver.event_list()) {
    if (e.name != nullptr) driver_events[e.name] = e.value;
  }
  counters["driver_events"] = driver_events;
  nlohmann::json estimate_status = nlohmann::json::object();
  for (std::size_t i = 0; i < models::kSampleStatusCount; ++i) {
    estimate_status[std::string(models::to_string(static_cast<models::SampleStatus>(i)))] =
        s.estimate_status[i];
  }
  counters["estimate_status"] = estimate_status;
  const auto path = daemon_->recorder().current_path();
  const RunningParameters running = daemon_->parameters();
  nlohmann::json filters = nlohmann::json::array();
  for (const FilterSection& f : running.filters)
    filters.push_back({{"type", f.type}, {"frequency_hz", f.frequency_hz}});
  nlohmann::json rt_problems = nlohmann::json::array();
  for (const std::string& p : daemon_->rt_setup().problems)
    rt_problems.push_back(p);
  nlohmann::json rt_notes = nlohmann::json::array();
  for (const std::string& n : daemon_->rt_setup().notes)
    rt_notes.push_back(n);
  return ok_reply({
      {"state", runtime::to_string(s.state)},
      {"mode", std::string(mode_name(s.mode))},
      {"driver", std::string(daemon_->driver().name())},
      {"faults", faults},
      {"fault_details", fault_details},
      {"counters", counters},
      {"timing",
       {{"rate_hz", daemon_->config().loop.rate_hz},
        {"overruns", s.overruns},
        {"missed_periods", s.missed_periods},
        {"last_overrun_cycle", s.last_overrun_cycle},
        {"wake_latency_ns",
         {{"p50", s.wake_latency_p50_ns},
          {"p99", s.wake_latency_p99_ns},
          {"max", s.wake_latency_max_ns}}},
        {"cycle_time_ns",
         {{"p50", s.cycle_time_p50_ns},
          {"p99", s.cycle_time_p99_ns},
          {"max", s.cycle_time_max_ns}}},
        {"degraded", daemon_->degraded_timing()},
        {"realtime_problems", rt_problems},
        {"realtime_notes", rt_notes}}},
      {"recording", {{"path", path ? nlohmann::json(path->string()) : nlohmann::json(nullptr)}}},
      {"estimate",
       {{"E", number_or_null(s.last.e)},
        {"D", number_or_null(s.last.d)},
        {"T_hat", number_or_null(s.last.t_hat)},
        {"S_hat", number_or_null(s.last.s_hat)},
        {"setpoint", number_or_null(s.last.setpoint)},
        {"command", number_or_null(s.last.command)},
        {"S", number_or_null(s.last.s_ref)},
        {"T", number_or_null(s.last.t_ref)},
        {"temp", number_or_null(s.last.temp_ref)}}},
      {"wave_running", s.wave_running},
      {"adaptation", adaptation_json(s.adaptation)},
      {"health", health_json(s.health, daemon_->health_state_at_start())},
      {"model",
       {{"path", running.model.string()},
        {"hash", hex(running.model_hash)},
        {"state_at_start", daemon_->model_state_at_start()}}},
      {"gains",
       {{"position",
         {{"kp", running.position.kp}, {"ki", running.position.ki}, {"kd", running.position.kd}}},
        {"force", {{"kp", running.force.kp}, {"ki", running.force.ki}, {"kd", running.force.kd}}}}},
      {"command_v_per_m", {running.command_min, running.command_max}},
      {"filters", filters},
  });
}

nlohmann::json ControlHandler::handle(const Request& request, const PeerCredentials& /*peer*/) {
  using runtime::CommandKind;
  if (std::holds_alternative<StatusRequest>(request)) return status();
  if (std::holds_alternative<ArmRequest>(request)) {
    if (!daemon_->may_arm()) {
      return error_reply(
          "arm: the loop has no real-time scheduling or locked memory (loop.allow_degraded_timing "
          "is false); see status timing.realtime_problems");
    }
    return send({0, CommandKind::kArm}, "arm");
  }
  if (std::holds_alternative<DisarmRequest>(request))
    return send({0, CommandKind::kDisarm}, "disarm");
  if (std::holds_alternative<ResetRequest>(request)) return send({0, CommandKind::kReset}, "reset");
  if (const auto* sp = std::get_if<SetpointRequest>(&request)) {
    return send({0, CommandKind::kSetpoint, sp->value}, "setpoint");
  }
  if (const auto* m = std::get_if<ModeRequest>(&request)) {
    return send({0, CommandKind::kMode, 0.0, m->mode}, "mode");
  }
  if (const auto* w = std::get_if<WaveRequest>(&request)) {
    if (w->stop) return send({0, CommandKind::kStopWave}, "wave");
    auto wave = std::make_unique<control::WaveGenerator>(w->wave, daemon_->config().sample_time());
    runtime::LoopCommand c{0, CommandKind::kWave};
    c.wave = wave.get();
    bool submitted = false;
    nlohmann::json reply = send(c, "wave", &submitted);
    // Once in the loop's ring the loop owns it (and hands it back through `retired`).
    if (submitted) static_cast<void>(wave.release());
    return reply;
  }
  if (const auto* r = std::get_if<RecordRequest>(&request)) {
    try {
      if (r->action == RecordRequest::Action::kStart) {
        return ok_reply({{"path", daemon_->recorder().start_file().string()}});
      }
      const auto path = daemon_->recorder().stop_file();
      return ok_reply({{"path", path ? nlohmann::json(path->string()) : nlohmann::json(nullptr)}});
    } catch (const std::exception& e) {
      return error_reply(std::string("record: ") + e.what());
    }
  }
  if (std::holds_alternative<StateRequest>(request)) {
    const Daemon::StateSaved saved = daemon_->dump_model_state();
    if (!saved.error.empty()) return error_reply("state: " + saved.error);
    return ok_reply({{"path", saved.path.string()}});
  }
  if (const auto* a = std::get_if<AdaptRequest>(&request)) {
    if (!daemon_->config().adaptation.enabled) {
      return error_reply("adapt: adaptation is off (adaptation.enabled in " +
                         daemon_->config().source.string() + "; a restart takes it)");
    }
    if (a->action == AdaptRequest::Action::kShow) {
      return ok_reply({{"adaptation", adaptation_json(daemon_->status().adaptation)}});
    }
    const bool freeze = a->action == AdaptRequest::Action::kFreeze;
    nlohmann::json reply = send({0, CommandKind::kAdapt, freeze ? 1.0 : 0.0}, "adapt");
    if (reply.value("ok", false)) reply["frozen"] = freeze;
    return reply;
  }
  if (const auto* i = std::get_if<ImpulseRequest>(&request)) {
    runtime::ForceInput* input = daemon_->force_input();
    if (input == nullptr) {
      return error_reply("impulse: the driver (" + std::string(daemon_->driver().name()) +
                         ") has no force input; the simulated transducer has one");
    }
    input->apply(i->force_n, i->duration_s);
    return ok_reply({{"force_n", i->force_n}, {"duration_s", i->duration_s}});
  }
  if (std::holds_alternative<ReloadRequest>(request)) {
    const ReloadResult reloaded = daemon_->reload();
    if (reloaded.ok()) {
      return ok_reply({{"reloaded", reloaded.model ? "gains, filters, limits, model"
                                                   : "gains, filters, limits"}});
    }
    std::string text;
    for (const std::string& p : reloaded.problems)
      text += (text.empty() ? "" : "; ") + p;
    return error_reply("reload: " + text);
  }
  return error_reply("unknown request");
}

}  // namespace selfsense::daemon
