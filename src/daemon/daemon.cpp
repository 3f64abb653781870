#include "selfsense/daemon/daemon.hpp"

#include <systemd/sd-daemon.h>

#include <cmath>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>

#include "selfsense/adaptation/adapted_reconstruction.hpp"
#include "selfsense/control/wave_generator.hpp"
#include "selfsense/daemon/health_report.hpp"
#include "selfsense/daemon/model_state_file.hpp"
#include "selfsense/daemon/prometheus.hpp"
#include "selfsense/daemon/recorder_metrics.hpp"
#include "selfsense/daemon/reload_keys.hpp"
#include "selfsense/daemon/telemetry_metrics.hpp"
#include "selfsense/model_io/model_yaml.hpp"
#include "selfsense/models/model_identity.hpp"
#include "selfsense/models/runtime_model.hpp"
#include "selfsense/runtime/controller.hpp"
#include "selfsense/runtime/supervisor.hpp"
#include "utc_stamp.hpp"

namespace selfsense::daemon {

// The recorder's ring as the loop's sample sink.
class Daemon::Sink final : public runtime::SampleSink {
 public:
  explicit Sink(Recorder& recorder) : recorder_(&recorder) {}
  bool push(const runtime::LoopSample& sample) noexcept override { return recorder_->push(sample); }

 private:
  Recorder* recorder_;
};

namespace {

RecorderConfig recorder_config(const DaemonConfig& c, const runtime::Driver& driver) {
  RecorderConfig r;
  r.directory = c.recorder.directory;
  r.prefix = "selfsensed";
  r.rotate_bytes = static_cast<std::size_t>(c.recorder.rotate_bytes);
  r.flush_period_ms = c.recorder.flush_ms;
  r.ring_capacity = c.recorder.ring_capacity;
  r.references = driver.has_references();
  r.temperature = driver.has_temperature();
  r.temperature_equivalent = c.adaptation.enabled;
  r.sample_time_s = c.sample_time();
  r.comments = {"config " + c.source.string(), "model " + c.model.string()};
  r.flight.seconds = c.recorder.flight_recorder_s;
  return r;
}

runtime::RtOptions rt_options(const LoopSection& loop) {
  runtime::RtOptions o;
  o.priority = loop.priority;
  o.cpu = loop.cpu;
  o.cpu_latency_us = loop.cpu_dma_latency_us;
  return o;
}

std::string fault_name(unsigned bit) {
  return std::string(runtime::to_string(static_cast<runtime::Fault>(bit)));
}

}  // namespace

Daemon::Daemon(DaemonConfig config, std::unique_ptr<runtime::Driver> driver,
               DriverSectionReader& driver_reader)
    : config_(std::move(config)), driver_reader_(&driver_reader), driver_(std::move(driver)) {
  const double ts = config_.sample_time();
  const models::TransducerModel model = models::load_model(config_.model);
  model_text_ = models::model_to_string(model);
  model_hash_ = models::parameter_hash(model);
  std::unique_ptr<models::Reconstruction> reconstruction;
  std::unique_ptr<adaptation::AdaptedReconstruction> adapted;
  if (config_.adaptation.enabled) {
    adapted = std::make_unique<adaptation::AdaptedReconstruction>(model,
                                                                  config_.adaptation.estimator, ts);
    state_buffer_ = adapted->make_saved_state();
    state_of_ = StateOf::kAdapted;
    restore_model_state(state_of_, [&adapted](const models::SavedState& saved) {
      return adapted->restore_state(saved);
    });
  } else {
    reconstruction = std::make_unique<models::Reconstruction>(model, models::RuntimeOptions{ts});
    state_buffer_ = reconstruction->make_saved_state();
    restore_model_state(state_of_, [&reconstruction](const models::SavedState& saved) {
      return reconstruction->restore_state(saved);
    });
  }
  const runtime::Controller controller(config_.control, model.actuator, ts);
  std::string why;
  if (!driver_->configure({ts}, &why)) throw std::runtime_error("driver: " + why);
  if (!driver_->activate(&why)) {
    driver_->deactivate();
    throw std::runtime_error("driver: " + why);
  }
  std::filesystem::create_directories(config_.recorder.directory);
  recorder_ = std::make_unique<Recorder>(recorder_config(config_, *driver_), fault_name);
  sink_ = std::make_unique<Sink>(*recorder_);
  loop_ = adapted
              ? std::make_unique<runtime::Loop>(config_.loop_config(), *driver_, std::move(adapted),
                                                controller, sink_.get())
              : std::make_unique<runtime::Loop>(config_.loop_config(), *driver_,
                                                std::move(reconstruction), controller, sink_.get());
  resume_health();
  runner_ = std::make_unique<runtime::LoopRunner>(
      *loop_, clock_, std::llround(ts * 1e9), rt_options(config_.loop), driver_->cycle_trigger());
}

void Daemon::resume_health() {
  health_buffer_.assign(loop_->health_state_size(), 0.0);
  if (health_buffer_.empty() || config_.model_state.empty()) return;  // "off"
  if (state_at_start_ != "restored") {
    health_at_start_ = state_at_start_ == "none" ? "none" : "not restored: nor the model's state";
  } else if (health_read_.empty()) {
    health_at_start_ = "none";
  } else if (!loop_->restore_health_state(health_read_)) {
    health_at_start_ = "not restored: " + config_.model_state.string() + ": " +
                       std::to_string(health_read_.size()) + " health values, this version " +
                       "keeps " + std::to_string(health_buffer_.size());
  } else {
    health_at_start_ = "restored";
  }
  health_read_.clear();
  static_cast<void>(
      std::fprintf(stderr, "selfsensed: health state: %s\n", health_at_start_.c_str()));
}

void Daemon::restore_model_state(
    StateOf running,
    const std::function<models::RestoreResult(const models::SavedState&)>& restore) {
  const std::filesystem::path& path = config_.model_state;
  if (path.empty()) return;
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    state_at_start_ = "none";
    return;
  }
  try {
    StateOf wrote = StateOf::kPlain;
    const models::SavedState saved = read_model_state(path, &wrote, &health_read_);
    if (wrote != running) {
      // The sizes differ too, but the reason is the configuration, not the file.
      state_at_start_ = "not restored: " + path.string() + ": written by the " +
                        std::string(to_string(wrote)) + " reconstruction, the daemon runs the " +
                        std::string(to_string(running)) + " one (adaptation.enabled)";
      static_cast<void>(
          std::fprintf(stderr, "selfsensed: model state: %s\n", state_at_start_.c_str()));
      return;
    }
    switch (restore(saved)) {
      case models::RestoreResult::kOk:
        state_at_start_ = "restored";  // the file is removed once the loop runs (run())
        break;
      case models::RestoreResult::kWrongModel:
        state_at_start_ = "not restored: " + path.string() + ": written by another model";
        break;
      case models::RestoreResult::kWrongSize:
        state_at_start_ = "not restored: " + path.string() + ": wrong number of values";
        break;
    }
  } catch (const std::exception& e) {
    state_at_start_ = std::string("not restored: ") + e.what();
  }
  static_cast<void>(std::fprintf(stderr, "selfsensed: model state: %s\n", state_at_start_.c_str()));
}

Daemon::StateSaved Daemon::save_model_state(const std::filesystem::path& path) {
  StateSaved out;
  const std::lock_guard lock(state_mutex_);
  runtime::LoopCommand c;
  c.kind = runtime::CommandKind::kSaveState;
  c.state = &state_buffer_;
  c.health_state = health_buffer_;
  const auto answer = command(c, std::chrono::milliseconds(500));
  if (!answer || answer->result != runtime::CommandResult::kDone) {
    out.error = "the loop did not save the model's state";
    return out;
  }
  try {
    write_model_state(path, state_buffer_, state_of_, health_buffer_);
  } catch (const std::exception& e) {
    out.error = e.what();
    return out;
  }
  out.path = path;
  return out;
}

Daemon::StateSaved Daemon::dump_model_state() {
  const std::string name = "model-state-" +
                           detail::utc_stamp(std::chrono::system_clock::now(), true) + "-cycle" +
                           std::to_string(loop_->status().cycle) + ".yaml";
  return save_model_state(config_.recorder.directory / name);
}

Daemon::~Daemon() {
  if (server_) server_->stop();
  if (runner_) runner_->stop();
  if (driver_) driver_->deactivate();
  if (recorder_) recorder_->stop();
  free_retired();
}

void Daemon::block_signals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGHUP);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
}

std::optional<runtime::LoopAnswer> Daemon::command(runtime::LoopCommand c,
                                                   std::chrono::milliseconds timeout,
                                                   bool* submitted) {
  const std::lock_guard lock(command_mutex_);
  if (submitted != nullptr) *submitted = false;
  c.id = ++next_id_;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!loop_->submit(c)) {
    if (std::chrono::steady_clock::now() > deadline) return std::nullopt;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  if (submitted != nullptr) *submitted = true;
  runtime::LoopAnswer a;
  while (std::chrono::steady_clock::now() <= deadline) {
    while (loop_->take_answer(a)) {
      if (a.id == c.id) return a;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  return std::nullopt;
}

void Daemon::free_retired() {
  if (!loop_) return;
  runtime::Retired r;
  while (loop_->take_retired(r)) {
    delete r.wave;         // NOLINT(cppcoreguidelines-owning-memory): handed back by the loop
    delete r.model;        // NOLINT(cppcoreguidelines-owning-memory)
    delete r.feedforward;  // NOLINT(cppcoreguidelines-owning-memory)
  }
}

namespace {

// A file copied over the old one while it is read ends mid-line far more often than not, and a
// cut inside a number can leave valid YAML with another value: a reload takes only a file that
// ends with a line break (every editor writes one; the model file has its own end marker).
bool ends_with_line_break(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in || in.tellg() <= 0) return false;
  in.seekg(-1, std::ios::end);
  char last = 0;
  return static_cast<bool>(in.get(last)) && last == '\n';
}

}  // namespace

ReloadResult Daemon::reload() {
  ReloadResult result;
  if (!ends_with_line_break(config_.source)) {
    result.problems.push_back(config_.source.string() +
                              ": does not end with a line break: taken as still being written "
                              "(save it whole, then reload)");
    return result;
  }
  ConfigResult next = load_config(config_.source, driver_reader_);
  if (!next.ok()) {
    result.problems = std::move(next.problems);
    return result;
  }
  const DaemonConfig& n = next.config;
  std::vector<std::string>& problems = result.problems;
  // Every key has a row in reload_keys.hpp; the live ones are applied below (the tuning), the
  // model only while disarmed, and a changed refused one is named.
  for (const std::string& key : refused_changes(config_, n)) {
    problems.push_back(config_.source.string() + ": " + key +
                       ": cannot change while running (restart the service)");
  }
  const runtime::ControllerConfig& nc = n.control;

  // The model, read once more: load_config checked it, but the file may have changed since.
  std::unique_ptr<models::Reconstruction> reconstruction;
  std::unique_ptr<runtime::Feedforward> feedforward;
  std::string model_text;
  std::uint64_t model_hash = 0;
  try {
    const models::TransducerModel model = models::load_model(n.model);
    model_text = models::model_to_string(model);
    model_hash = models::parameter_hash(model);
    if (model_text != model_text_ && config_.adaptation.enabled) {
      problems.push_back("model: " + n.model.string() +
                         ": a new model is not taken while adaptation is enabled (the learned "
                         "drift is relative to the running model); restart the service");
    } else if (model_text != model_text_) {
      const double ts = config_.sample_time();
      reconstruction = std::make_unique<models::Reconstruction>(model, models::RuntimeOptions{ts});
      feedforward = std::make_unique<runtime::Feedforward>(
          runtime::make_feedforward(config_.control, model.actuator, ts));
    }
  } catch (const std::exception& e) {
    problems.push_back(std::string("model: ") + e.what());
  }
  if (!problems.empty()) return result;

  if (reconstruction) {
    models::SavedState next_buffer = reconstruction->make_saved_state();
    runtime::LoopCommand c;
    c.kind = runtime::CommandKind::kSwapModel;
    c.model = reconstruction.get();
    c.feedforward = feedforward.get();
    bool submitted = false;
    const auto answer = command(c, std::chrono::milliseconds(500), &submitted);
    if (submitted) {  // the loop owns them now (it hands back what it refuses)
      static_cast<void>(reconstruction.release());
      static_cast<void>(feedforward.release());
    }
    if (!answer || answer->result != runtime::CommandResult::kDone) {
      problems.push_back(
          "model: " + n.model.string() +
          (answer && answer->result == runtime::CommandResult::kRefusedState
               ? ": a new model is taken only while disarmed (the loop is armed); disarm and "
                 "reload"
               : ": the loop did not take the new model"));
      return result;
    }
    {
      const std::lock_guard state_lock(state_mutex_);
      state_buffer_ = std::move(next_buffer);
    }
    const std::lock_guard lock(parameters_mutex_);
    config_.model = n.model;
    model_text_ = std::move(model_text);
    model_hash_ = model_hash;
    result.model = true;
  }
  runtime::LoopCommand c;
  c.kind = runtime::CommandKind::kTune;
  c.tuning = runtime::tuning_of(nc);
  const auto answer = command(c, std::chrono::milliseconds(500));
  if (!answer || answer->result != runtime::CommandResult::kDone) {
    problems.push_back(config_.source.string() +
                       ": control: the loop refused the new gains, filters or command limits");
    return result;
  }
  const std::lock_guard lock(parameters_mutex_);
  config_.control.position.gains = nc.position.gains;
  config_.control.force.gains = nc.force.gains;
  config_.control.filters = nc.filters;
  config_.control.filter_count = nc.filter_count;
  config_.control.command_min = nc.command_min;
  config_.control.command_max = nc.command_max;
  config_.filters = n.filters;
  result.tuning = true;
  return result;
}

RunningParameters Daemon::parameters() const {
  const std::lock_guard lock(parameters_mutex_);
  return {config_.model,
          model_hash_,
          config_.control.position.gains,
          config_.control.force.gains,
          config_.filters,
          config_.control.command_min,
          config_.control.command_max};
}

void Daemon::notify_status() {
  const runtime::StatusSnapshot s = loop_->status();
  std::string faults;
  for (std::size_t i = 0; i < runtime::kFaultCount; ++i) {
    if ((s.faults & runtime::bit(static_cast<runtime::Fault>(i))) == 0U) continue;
    faults += faults.empty() ? "" : ",";
    faults += runtime::to_string(static_cast<runtime::Fault>(i));
  }
  const std::string line = std::string("STATUS=") + runtime::to_string(s.state) + ", cycle " +
                           std::to_string(s.cycle) + ", faults [" + faults + "]" +
                           (degraded_timing() ? ", degraded timing" : "");
  static_cast<void>(sd_notify(0, line.c_str()));
}

void Daemon::write_telemetry() {
  if (config_.telemetry.prometheus_file.empty()) return;
  const runtime::StatusSnapshot s = loop_->status();
  try {
    std::vector<MetricFamily> families = loop_metrics(s);
    for (MetricFamily& f : adaptation_metrics(s.adaptation))
      families.push_back(std::move(f));
    for (MetricFamily& f : health_metrics(s.health))
      families.push_back(std::move(f));
    for (MetricFamily& f : driver_metrics(driver_->name(), s.driver))
      families.push_back(std::move(f));
    for (MetricFamily& f : recorder_metrics(recorder_->counters()))
      families.push_back(std::move(f));
    write_textfile(config_.telemetry.prometheus_file, format_exposition(families));
  } catch (const std::exception& e) {
    static_cast<void>(std::fprintf(stderr, "selfsensed: telemetry: %s\n", e.what()));
  }
}

int Daemon::run() {
  recorder_->start();
  if (config_.recorder.record_at_start) static_cast<void>(recorder_->start_file());
  rt_setup_ = runner_->start();
  if (state_at_start_ == "restored") {
    // Taken once: after a crash the actuator's history is unknown, and a state from before it
    // would be stale. The next clean stop writes it again.
    std::error_code ec;
    std::filesystem::remove(config_.model_state, ec);
  }
  for (const std::string& p : rt_setup_.problems) {
    static_cast<void>(std::fprintf(
        stderr, "selfsensed: real-time set-up: %s%s\n", p.c_str(),
        config_.loop.allow_degraded_timing ? " (degraded timing allowed)" : " (arming refused)"));
  }
  for (const std::string& n : rt_setup_.notes) {
    static_cast<void>(std::fprintf(stderr, "selfsensed: real-time set-up: %s (note)\n", n.c_str()));
  }
  ControlServerConfig server_config;
  server_config.path = config_.socket.path;
  server_config.group = config_.socket.group;
  server_config.max_clients = static_cast<std::size_t>(config_.socket.max_clients);
  std::filesystem::create_directories(server_config.path.parent_path());
  handler_ = std::make_unique<ControlHandler>(*this);
  server_ = std::make_unique<ControlServer>(server_config, *handler_, [](std::string_view line) {
    static_cast<void>(std::fprintf(stderr, "selfsensed: socket: %.*s\n",
                                   static_cast<int>(line.size()), line.data()));
  });
  server_->start();
  static_cast<void>(sd_notify(0, "READY=1"));
  std::printf("selfsensed: running at %g Hz, driver %s, model %s\n", config_.loop.rate_hz,
              std::string(driver_->name()).c_str(), config_.model.string().c_str());
  static_cast<void>(std::fflush(stdout));

  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGHUP);
  std::uint64_t last_progress = runner_->progress();
  auto last_status = std::chrono::steady_clock::now();
  auto last_telemetry = last_status;
  while (!stop_requested_.load()) {
    const timespec wait{0, 100'000'000};
    const int sig = sigtimedwait(&set, nullptr, &wait);
    if (sig == SIGTERM || sig == SIGINT) break;
    if (sig == SIGHUP) {
      static_cast<void>(sd_notify(0, "RELOADING=1"));
      const ReloadResult reloaded = reload();
      for (const std::string& p : reloaded.problems)
        static_cast<void>(std::fprintf(stderr, "selfsensed: reload refused: %s\n", p.c_str()));
      if (reloaded.ok()) {
        static_cast<void>(std::fprintf(stderr, "selfsensed: reloaded gains, filters, limits%s\n",
                                       reloaded.model ? " and the model" : ""));
      }
      static_cast<void>(sd_notify(0, "READY=1"));
    }
    const std::uint64_t progress = runner_->progress();
    if (progress != last_progress) static_cast<void>(sd_notify(0, "WATCHDOG=1"));
    last_progress = progress;
    free_retired();
    const auto now = std::chrono::steady_clock::now();
    if (now - last_status >= std::chrono::seconds(1)) {
      notify_status();
      last_status = now;
    }
    if (now - last_telemetry >= std::chrono::duration<double>(config_.telemetry.period_s)) {
      write_telemetry();
      last_telemetry = now;
    }
  }
  static_cast<void>(sd_notify(0, "STOPPING=1"));
  server_->stop();
  // Safe output first, then stop. While armed the command ramps down to the safe output over
  // safety.stop_ramp_s (a step would ring the mount: tension in a stack that does not take it);
  // the loop disarms itself at the ramp's end. The disarm after it is for every other case.
  const double ramp = config_.safety.stop_ramp_s;
  if (ramp > 0.0 && loop_->status().state == runtime::LoopState::kArmed) {
    const auto accepted =
        command({0, runtime::CommandKind::kRampDown, ramp}, std::chrono::milliseconds(100));
    if (accepted && accepted->result == runtime::CommandResult::kDone) {
      const auto until =
          std::chrono::steady_clock::now() + std::chrono::duration<double>(ramp + 0.5);
      while (loop_->status().state == runtime::LoopState::kArmed &&
             std::chrono::steady_clock::now() < until) {
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
      }
    }
  }
  static_cast<void>(command({0, runtime::CommandKind::kDisarm}, std::chrono::milliseconds(100)));
  if (!config_.model_state.empty()) {
    const StateSaved saved = save_model_state(config_.model_state);
    if (!saved.error.empty()) {
      static_cast<void>(
          std::fprintf(stderr, "selfsensed: model state not saved: %s\n", saved.error.c_str()));
    }
  }
  runner_->stop();
  driver_->deactivate();
  recorder_->stop();
  free_retired();
  std::printf("selfsensed: stopped at cycle %lld\n",
              static_cast<long long>(loop_->local_status().cycle));
  return 0;
}

}  // namespace selfsense::daemon
