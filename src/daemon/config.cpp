#include "selfsense/daemon/config.hpp"

#include <cmath>
#include <exception>
#include <span>
#include <string_view>

#include "selfsense/adaptation/adapted_reconstruction.hpp"
#include "selfsense/base/check.hpp"
#include "selfsense/base/format_number.hpp"
#include "selfsense/model_io/model_yaml.hpp"

namespace selfsense::daemon {
namespace {

using io::YamlMap;

// Collects the problems found after loading, each located at its key.
class Problems {
 public:
  Problems(const YamlMap& root, std::vector<std::string>& out) : root_(&root), out_(&out) {}
  void add(const std::string& key_path_and_message) {
    out_->push_back(root_->locate(key_path_and_message));
  }
  void check(bool ok, const std::string& key, const std::string& message) {
    if (!ok) add(key + ": " + message);
  }
  // base::check's message: "<key>: <value> <constraint>".
  template <typename T>
  void require(bool ok, const std::string& key, T value, std::string_view constraint) {
    if (!ok) add(base::check::violation(key, value, constraint));
  }

 private:
  const YamlMap* root_;
  std::vector<std::string>* out_;
};

// YAML integers arrive as 64 bits; the fields are 32.
void read_u32(YamlMap& map, std::string_view key, std::uint32_t& out) {
  std::uint64_t v = out;
  map.read(key, v);
  if (v > 0xffffffffULL) map.fail(key, "must be < 2^32");
  out = static_cast<std::uint32_t>(v);
}

Range read_range(YamlMap& map, std::string_view key, Range fallback) {
  std::vector<double> v{fallback.min, fallback.max};
  map.read_sequence(key, v);
  if (v.size() != 2) map.fail(key, "expected [min, max]");
  return {v[0], v[1]};
}

control::Pid::Params read_pid(YamlMap m) {
  control::Pid::Params p;
  m.read("kp", p.gains.kp);
  m.read("ki", p.gains.ki);
  m.read("kd", p.gains.kd);
  m.read("derivative_filter_s", p.derivative_filter_time);
  m.read("setpoint_weight", p.setpoint_weight);
  m.read("tracking_time_s", p.tracking_time);
  m.finish();
  return p;
}

control::SetpointShaper::Params read_shaper(YamlMap m) {
  control::SetpointShaper::Params p;
  m.read("slew_per_s", p.slew_rate);
  std::string filter = "none";
  m.read("filter", filter);
  if (filter == "none") {
    p.filter = control::SetpointShaper::Filter::kNone;
  } else if (filter == "first-order") {
    p.filter = control::SetpointShaper::Filter::kFirstOrder;
  } else if (filter == "second-order") {
    p.filter = control::SetpointShaper::Filter::kSecondOrder;
  } else {
    m.fail("filter", "'" + filter + "' is not one of none, first-order, second-order");
  }
  m.read("time_constant_s", p.time_constant);
  m.finish();
  return p;
}

control::DampingController::Params read_damping(YamlMap m) {
  control::DampingController::Params p;
  std::string law = "ppf";
  m.read("law", law);
  if (law == "ppf") {
    p.law = control::DampingController::Law::kPositivePosition;
  } else if (law == "velocity") {
    p.law = control::DampingController::Law::kVelocity;
  } else {
    m.fail("law", "'" + law + "' is not one of ppf, velocity");
  }
  m.read("gain", p.gain);
  m.read("frequency_hz", p.frequency);
  m.read("damping", p.damping);
  m.read("dc_block_hz", p.dc_block_frequency);
  m.finish();
  return p;
}

runtime::ControlMode parse_mode(YamlMap& m, std::string_view key, const std::string& name) {
  if (name == "position") return runtime::ControlMode::kPosition;
  if (name == "force") return runtime::ControlMode::kForce;
  if (name == "open-loop") return runtime::ControlMode::kOpenLoop;
  if (name == "damping") return runtime::ControlMode::kDamping;
  m.fail(key, "'" + name + "' is not one of position, force, open-loop, damping");
}

void read_control(YamlMap c, DaemonConfig& cfg) {
  std::string mode = "position";
  c.read("mode", mode);
  cfg.control.mode = parse_mode(c, "mode", mode);
  c.read("feedforward", cfg.control.feedforward);
  const Range command = read_range(c, "command_v_per_m", {0.0, 2e6});
  cfg.control.command_min = command.min;
  cfg.control.command_max = command.max;
  c.read("force_direction", cfg.control.force_direction);
  if (auto m = c.optional_map("position")) cfg.control.position = read_pid(*m);
  if (auto m = c.optional_map("force")) cfg.control.force = read_pid(*m);
  if (auto m = c.optional_map("position_shaper")) cfg.control.position_shaper = read_shaper(*m);
  if (auto m = c.optional_map("force_shaper")) cfg.control.force_shaper = read_shaper(*m);
  if (auto m = c.optional_map("damping")) cfg.control.damping = read_damping(*m);
  for (YamlMap f : c.maps("filters")) {
    FilterSection s;
    s.type = f.required<std::string>("type");
    f.read("frequency_hz", s.frequency_hz);
    f.read("quality", s.quality);
    f.read("bandwidth_hz", s.bandwidth_hz);
    f.read("depth_db", s.depth_db);
    f.finish();
    cfg.filters.push_back(s);
  }
  c.finish();
}

void read_safety(YamlMap s, SafetySection& out) {
  std::string safe = "zero";
  s.read("safe_output", safe);
  if (safe == "zero") {
    out.safe_output = runtime::SafeOutput::kZero;
  } else if (safe == "hold") {
    out.safe_output = runtime::SafeOutput::kHold;
  } else {
    s.fail("safe_output", "'" + safe + "' is not one of zero, hold");
  }
  s.read("safe_value_v_per_m", out.safe_value_v_per_m);
  out.strain = read_range(s, "strain_range", out.strain);
  out.stress_pa = read_range(s, "stress_range_pa", out.stress_pa);
  out.setpoint_strain = read_range(s, "setpoint_strain", out.setpoint_strain);
  out.setpoint_stress_pa = read_range(s, "setpoint_stress_pa", out.setpoint_stress_pa);
  if (auto o = s.optional_map("overrun")) {
    read_u32(*o, "consecutive", out.overrun.consecutive);
    read_u32(*o, "within_count", out.overrun.within_count);
    read_u32(*o, "window_cycles", out.overrun.window);
    o->finish();
  }
  s.read("watchdog_s", out.watchdog_s);
  s.read("stop_ramp_s", out.stop_ramp_s);
  s.finish();
}

void read_recorder(YamlMap r, RecorderSection& out, const std::filesystem::path& base) {
  std::string dir = out.directory.string();
  r.read("directory", dir);
  out.directory = base / dir;
  r.read("rotate_bytes", out.rotate_bytes);
  r.read("flush_ms", out.flush_ms);
  std::uint64_t ring = out.ring_capacity;
  r.read("ring_capacity", ring);
  out.ring_capacity = static_cast<std::size_t>(ring);
  r.read("flight_recorder_s", out.flight_recorder_s);
  r.read("record_at_start", out.record_at_start);
  r.finish();
}

void read_socket(YamlMap s, SocketSection& out, const std::filesystem::path& base) {
  std::string path = out.path.string();
  s.read("path", path);
  out.path = base / path;
  s.read("group", out.group);
  s.read("max_clients", out.max_clients);
  s.finish();
}

void read_adaptation(YamlMap a, AdaptationSection& out) {
  adaptation::DriftEstimatorConfig& e = out.estimator;
  a.read("enabled", out.enabled);
  a.read("frozen", e.frozen);
  a.read("learn_loop", e.learn_loop);
  a.read("min_field_step_v_per_m", e.min_field_step_v_per_m);
  a.read("max_interval_s", e.max_interval_s);
  a.read("memory_updates", e.memory_updates);
  a.read("initial_variance", e.initial_variance);
  a.read("process_noise_per_s", e.process_noise_per_s);
  a.read("max_relative_change", e.max_relative_change);
  a.read("reference_degc", e.reference_degc);
  a.read("permittivity_per_k", e.permittivity_per_k);
  a.read("loop_per_k", e.loop_per_k);
  a.read("coupling_per_k", e.coupling_per_k);
  a.read("compliance_per_k", e.compliance_per_k);
  a.read("load_stiffness_ratio", e.load_stiffness_ratio);
  a.read("thermal_model", e.thermal.enabled);
  a.read("thermal_resistance_k_per_w", e.thermal.resistance_k_per_w);
  a.read("thermal_time_constant_s", e.thermal.time_constant_s);
  a.read("ambient_degc", e.thermal.ambient_degc);
  a.read("stack_volume_m3", e.thermal.stack_volume_m3);
  a.read("max_power_w", e.thermal.max_power_w);
  a.read("use_temperature", out.use_temperature);
  a.read("feedforward_estimate", out.feedforward_estimate);
  a.finish();
}

void read_health(YamlMap h, HealthSection& out) {
  adaptation::HealthEstimatorConfig& e = out.estimator;
  adaptation::HealthBands& b = out.bands;
  h.read("enabled", out.enabled);
  h.read("fault", b.fault);
  h.read("max_temperature_degc", b.max_temperature_degc);
  h.read("max_depolarisation_pct", b.max_depolarisation_pct);
  h.read("min_leakage_resistivity_ohm_m", b.min_leakage_resistivity_ohm_m);
  h.read("reversal_field_v_per_m", e.reversal_field_v_per_m);
  h.read("settle_s", e.settle_s);
  read_u32(h, "baseline_cycles", e.baseline_cycles);
  h.read("span_tolerance", e.span_tolerance);
  h.read("hold_field_v_per_m", e.hold_field_v_per_m);
  h.read("hold_settle_s", e.hold_settle_s);
  h.read("hold_window_s", e.hold_window_s);
  h.read("min_hold_field_v_per_m", e.min_hold_field_v_per_m);
  h.read("trend_time_s", e.trend_time_s);
  h.read("slope_time_s", e.slope_time_s);
  h.read("capacitance_per_k", e.capacitance_per_k);
  h.read("dissipation_per_k", e.dissipation_per_k);
  h.read("depolarisation_sensitivity", e.depolarisation_sensitivity);
  h.read("model_reference", e.model_reference);
  h.read("max_span_change", e.max_span_change);
  h.finish();
}

// Value and cross-field rules, every problem collected.
void validate(const DaemonConfig& c, Problems& p) {
  const double fs = c.loop.rate_hz;
  p.require(fs >= 100.0 && fs <= 100000.0, "loop.rate_hz", fs, "must be within [100, 100000]");
  p.require(c.loop.priority >= 1 && c.loop.priority <= 99, "loop.priority", c.loop.priority,
            "must be within [1, 99] (SCHED_FIFO)");
  p.check(c.loop.cpu >= -1, "loop.cpu", "must be -1 (any) or a CPU index");
  p.require(c.loop.cpu_dma_latency_us >= -1 && c.loop.cpu_dma_latency_us <= 1000000,
            "loop.cpu_dma_latency_us", c.loop.cpu_dma_latency_us,
            "must be -1 (no request) or within [0, 1000000]");
  p.check(c.loop.status_period_cycles >= 1, "loop.status_period_cycles", "must be >= 1");
  if (!(fs > 0.0)) return;
  const double ts = 1.0 / fs;
  std::string why;
  const runtime::ControllerConfig& k = c.control;
  p.check(k.command_min < k.command_max, "control.command_v_per_m", "min must be < max");
  p.check(k.force_direction == 1.0 || k.force_direction == -1.0, "control.force_direction",
          "must be 1 or -1");
  for (const auto& [name, pid] :
       {std::pair{"control.position", &k.position}, std::pair{"control.force", &k.force}}) {
    if (!pid->is_valid(ts, &why)) p.add(std::string(name) + ": " + why);
  }
  if (k.damping.gain > 0.0 && !k.damping.is_valid(ts, &why)) p.add("control.damping: " + why);
  if (!k.position_shaper.is_valid(ts, &why)) p.add("control.position_shaper: " + why);
  if (!k.force_shaper.is_valid(ts, &why)) p.add("control.force_shaper: " + why);
  for (std::size_t i = 0; i < c.filters.size(); ++i) {
    const FilterSection& f = c.filters[i];
    const std::string key = "control.filters[" + std::to_string(i) + "]";
    if (f.frequency_hz >= 0.45 * fs) {
      p.add(key + ".frequency_hz: " + base::format_number(f.frequency_hz) +
            " Hz must be below 0.45 of the loop rate (" + base::format_number(0.45 * fs) + " Hz)");
    }
  }
  if (c.filters.size() > control::FilterChain::kMaxSections) {
    p.add("control.filters: at most " + std::to_string(control::FilterChain::kMaxSections) +
          " sections");
  }
  const SafetySection& s = c.safety;
  p.check(s.strain.min < s.strain.max, "safety.strain_range", "min must be < max");
  p.check(s.stress_pa.min < s.stress_pa.max, "safety.stress_range_pa", "min must be < max");
  p.check(s.setpoint_strain.min >= s.strain.min && s.setpoint_strain.max <= s.strain.max &&
              s.setpoint_strain.min < s.setpoint_strain.max,
          "safety.setpoint_strain", "must be an interval inside safety.strain_range");
  p.check(s.setpoint_stress_pa.min >= s.stress_pa.min &&
              s.setpoint_stress_pa.max <= s.stress_pa.max &&
              s.setpoint_stress_pa.min < s.setpoint_stress_pa.max,
          "safety.setpoint_stress_pa", "must be an interval inside safety.stress_range_pa");
  p.check(s.safe_value_v_per_m >= k.command_min && s.safe_value_v_per_m <= k.command_max,
          "safety.safe_value_v_per_m", "must be inside control.command_v_per_m");
  if (!s.overrun.is_valid(&why)) p.add(why);
  p.check(s.watchdog_s >= 0.0, "safety.watchdog_s", "must be >= 0");
  p.require(s.stop_ramp_s >= 0.0 && s.stop_ramp_s <= 10.0, "safety.stop_ramp_s", s.stop_ramp_s,
            "must be within [0, 10] s");
  const RecorderSection& r = c.recorder;
  p.check(r.rotate_bytes >= 4096, "recorder.rotate_bytes", "must be >= 4096");
  p.check(r.flush_ms >= 1.0 && r.flush_ms <= 60000.0, "recorder.flush_ms",
          "must be within [1, 60000]");
  p.check(r.ring_capacity >= 1024, "recorder.ring_capacity", "must be >= 1024");
  p.check(r.flight_recorder_s >= 0.0 && r.flight_recorder_s <= 60.0, "recorder.flight_recorder_s",
          "must be within [0, 60]");
  p.check(c.socket.max_clients >= 1 && c.socket.max_clients <= 1024, "socket.max_clients",
          "must be within [1, 1024]");
  p.check(c.telemetry.period_s > 0.0, "telemetry.period_s", "must be > 0");
  // Checked whether enabled or not: a section that is switched on later must already be valid.
  if (!c.adaptation.estimator.is_valid("adaptation.", &why)) p.add(why);
  if (!c.health.estimator.is_valid("health.", &why)) p.add(why);
  if (!c.health.bands.is_valid("health.", &why)) p.add(why);
}

// The model must reconstruct from what the drivers measure (E and D, field drive).
void check_model(const DaemonConfig& c, Problems& p) {
  try {
    const models::TransducerModel m = models::load_model(c.model);
    if (m.drive() != models::Drive::kField) {
      p.add("model: " + c.model.string() + " is a " + std::string(models::to_string(m.structure)) +
            " model (charge drive); the drivers drive the field E and measure D");
    }
    if (!models::can_reconstruct(m)) {
      p.add("model: " + c.model.string() +
            " cannot reconstruct stress (no sensor side with a stress coupling)");
    } else if (c.adaptation.enabled && c.adaptation.estimator.is_valid("", nullptr)) {
      try {  // the model must be one the adaptation runs (field drive, no corrections)
        static_cast<void>(
            adaptation::AdaptedReconstruction(m, c.adaptation.estimator, c.sample_time()));
      } catch (const std::exception& e) {
        p.add("adaptation.enabled: " + c.model.string() + ": " + e.what());
      }
    }
  } catch (const std::exception& e) {
    p.add(std::string("model: ") + e.what());
  }
}

}  // namespace

runtime::LoopConfig DaemonConfig::loop_config() const {
  runtime::LoopConfig l;
  l.sample_time = sample_time();
  l.safe_output = safety.safe_output;
  l.safe_value = safety.safe_value_v_per_m;
  l.strain_min = safety.strain.min;
  l.strain_max = safety.strain.max;
  l.stress_min = safety.stress_pa.min;
  l.stress_max = safety.stress_pa.max;
  l.overrun = safety.overrun;
  l.watchdog_s = safety.watchdog_s;
  l.status_period = loop.status_period_cycles;
  l.adaptation_temperature = adaptation.enabled && adaptation.use_temperature;
  l.adaptation_feedforward_estimate = adaptation.enabled && adaptation.feedforward_estimate;
  l.health_enabled = health.enabled;
  l.health = health.estimator;
  l.health_bands = health.bands;
  return l;
}

ConfigResult load_config(const std::filesystem::path& path, DriverSectionReader* driver_reader) {
  ConfigResult result;
  DaemonConfig& c = result.config;
  c.source = path;
  const std::filesystem::path base = path.parent_path();
  try {
    YamlMap root = YamlMap::load_file(path);
    const int version = root.required<int>("selfsensed");
    if (version != kConfigFormatVersion) {
      root.fail("selfsensed", "format version " + std::to_string(version) +
                                  " is not supported (this build reads " +
                                  std::to_string(kConfigFormatVersion) + ")");
    }
    if (auto l = root.optional_map("loop")) {
      l->read("rate_hz", c.loop.rate_hz);
      l->read("priority", c.loop.priority);
      l->read("cpu", c.loop.cpu);
      l->read("cpu_dma_latency_us", c.loop.cpu_dma_latency_us);
      l->read("allow_degraded_timing", c.loop.allow_degraded_timing);
      read_u32(*l, "status_period_cycles", c.loop.status_period_cycles);
      l->finish();
    }
    c.model = base / root.required<std::string>("model");
    std::string state;
    root.read("model_state", state);
    if (!state.empty()) c.model_state = base / state;
    YamlMap driver = root.map("driver");
    c.driver_type = driver.required<std::string>("type");
    c.driver_section = driver.canonical_text();
    if (auto m = root.optional_map("control")) read_control(*m, c);
    if (auto m = root.optional_map("safety")) read_safety(*m, c.safety);
    if (auto m = root.optional_map("recorder")) read_recorder(*m, c.recorder, base);
    if (auto m = root.optional_map("socket")) read_socket(*m, c.socket, base);
    if (auto m = root.optional_map("telemetry")) {
      std::string prom;
      m->read("prometheus_file", prom);
      if (!prom.empty()) c.telemetry.prometheus_file = base / prom;
      m->read("period_s", c.telemetry.period_s);
      m->finish();
    }
    if (auto m = root.optional_map("adaptation")) read_adaptation(*m, c.adaptation);
    if (auto m = root.optional_map("health")) read_health(*m, c.health);
    Problems problems(root, result.problems);
    validate(c, problems);
    if (!c.model.empty()) check_model(c, problems);
    if (driver_reader != nullptr) {
      driver_reader->read(driver, c, result.problems);
    } else {
      result.problems.push_back(root.locate("driver.type: no driver registry to read it"));
    }
    driver.finish();
    root.finish();
    result.known_keys.assign(root.known_keys().begin(), root.known_keys().end());
    // Filters designed for the loop (the design checks what validate() does not).
    for (std::size_t i = 0; i < c.filters.size() && i < control::FilterChain::kMaxSections; ++i) {
      const FilterSection& f = c.filters[i];
      const double ts = c.sample_time();
      if (f.frequency_hz >= 0.45 * c.loop.rate_hz) continue;  // reported by validate()
      try {
        if (f.type == "notch") {
          c.control.filters[i] =
              control::notch({f.frequency_hz, f.quality, f.bandwidth_hz, f.depth_db}, ts);
        } else if (f.type == "low-pass") {
          c.control.filters[i] = control::low_pass(
              control::SecondOrderDesign{f.frequency_hz, f.quality > 0 ? f.quality : 0.7071}, ts);
        } else if (f.type == "high-pass") {
          c.control.filters[i] = control::high_pass(
              control::SecondOrderDesign{f.frequency_hz, f.quality > 0 ? f.quality : 0.7071}, ts);
        } else if (f.type == "low-pass-1") {
          c.control.filters[i] = control::low_pass(control::FirstOrderDesign{f.frequency_hz}, ts);
        } else if (f.type == "high-pass-1") {
          c.control.filters[i] = control::high_pass(control::FirstOrderDesign{f.frequency_hz}, ts);
        } else {
          problems.add("control.filters[" + std::to_string(i) + "].type: '" + f.type +
                       "' is not one of notch, low-pass, high-pass, low-pass-1, high-pass-1");
          continue;
        }
        c.control.filter_count = i + 1;
      } catch (const std::exception& e) {
        problems.add("control.filters[" + std::to_string(i) + "]: " + e.what());
      }
    }
  } catch (const io::YamlError& e) {
    result.problems.emplace_back(e.what());
  } catch (const std::exception& e) {
    result.problems.push_back(path.string() + ": " + e.what());
  }
  return result;
}

}  // namespace selfsense::daemon
