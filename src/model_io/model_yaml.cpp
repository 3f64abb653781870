#include "selfsense/model_io/model_yaml.hpp"

#include <fcntl.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <array>
#include <cerrno>
#include <optional>
#include <stdexcept>
#include <string_view>
#include <utility>

#include "geometry_fields.hpp"
#include "selfsense/base/errno_text.hpp"
#include "selfsense/io/yaml_map.hpp"

namespace selfsense::models {
namespace {

using io::YamlMap;
using operators::HysteresisCreep;

// Validation messages name parameters by class ("PrandtlIshlinskii.weights[1]: ..."); the user
// knows them by key path ("sensor.hysteresis.weights[1]: ...").
std::string renamed(const std::string& why, std::string_view class_prefix,
                    const std::string& key_path) {
  if (why.rfind(class_prefix, 0) == 0) return key_path + why.substr(class_prefix.size());
  return key_path + ": " + why;
}

template <typename Params>
void validate(const YamlMap& map, const Params& params, std::string_view class_prefix,
              const std::string& key) {
  std::string why;
  if (!params.is_valid(&why)) {
    throw io::YamlError(map.locate(renamed(why, class_prefix, map.path(key) + ".")));
  }
}

HysteresisCreep::Params read_operator(YamlMap& side) {
  HysteresisCreep::Params p;
  YamlMap h = side.map("hysteresis");
  p.hysteresis.linear_weight = h.required<double>("linear_weight");
  h.read_sequence("thresholds", p.hysteresis.thresholds);
  h.read_sequence("weights", p.hysteresis.weights);
  h.finish();
  validate(side, p.hysteresis, "PrandtlIshlinskii.", "hysteresis");
  if (auto s = side.optional_map("superposition")) {
    s->read("linear_weight", p.superposition.linear_weight);
    s->read_sequence("upper_thresholds", p.superposition.upper_thresholds);
    s->read_sequence("upper_weights", p.superposition.upper_weights);
    s->read_sequence("lower_thresholds", p.superposition.lower_thresholds);
    s->read_sequence("lower_weights", p.superposition.lower_weights);
    s->finish();
    validate(side, p.superposition, "DeadZoneSuperposition.", "superposition");
  }
  if (auto c = side.optional_map("creep")) {
    c->read_sequence("thresholds", p.creep.thresholds);
    c->read_sequence("eigenvalues", p.creep.eigenvalues);
    c->read_sequence("weights", p.creep.weights);
    c->finish();
    validate(side, p.creep, "ThresholdCreep.", "creep");
  }
  if (auto g = side.optional_map("hinges")) {
    g->read_sequence("thresholds", p.hinges.thresholds);
    g->read_sequence("levels", p.hinges.levels);
    g->read_sequence("weights", p.hinges.weights);
    g->finish();
    validate(side, p.hinges, "PlayHinges.", "hinges");
  }
  return p;
}

std::optional<SideModel> read_side(YamlMap& root, std::string_view key, double ts) {
  std::optional<YamlMap> side = root.optional_map(key);
  if (!side) return std::nullopt;
  SideModel m;
  m.sample_time = ts;
  m.linear_gains = {side->optional<double>("coupling", 0.0)};
  side->read("offset", m.offset);
  side->read("quadratic", m.quadratic);
  side->read_sequence("history", m.history);
  m.op = read_operator(*side);
  side->finish();
  return m;
}

std::optional<StressHysteresisSide> read_vectorial_side(YamlMap& v, std::string_view key) {
  std::optional<YamlMap> m = v.optional_map(key);
  if (!m) return std::nullopt;
  StressHysteresisSide side;
  m->read_sequence("base", side.base);
  m->read_sequence("stress", side.stress);
  side.linear = m->required<double>("linear");
  m->read("quadratic", side.quadratic);
  m->read("offset", side.offset);
  m->finish();
  return side;
}

StressHysteresisModel read_vectorial(YamlMap& root, double ts) {
  YamlMap v = root.map("vectorial");
  StressHysteresisModel m;
  m.sample_time = ts;
  v.read_sequence("thresholds", m.basis.thresholds);
  v.read_sequence("history", m.history);
  if (std::optional<YamlMap> creep = v.optional_map("creep")) {
    creep->read_sequence("rows", m.basis.creep_rows);
    creep->read_sequence("eigenvalues", m.basis.eigenvalues);
    creep->finish();
  }
  std::vector<double> range;
  v.read_sequence("stress_range", range);
  if (range.size() != 2) v.fail("stress_range", "expected [min, max]");
  m.stress_min = range[0];
  m.stress_max = range[1];
  m.sensor = read_vectorial_side(v, "sensor");
  m.actuator = read_vectorial_side(v, "actuator");
  v.finish();
  return m;
}

std::optional<InputRange> read_range(YamlMap& map, std::string_view key) {
  if (!map.has(key)) return std::nullopt;
  std::vector<double> range;
  map.read_sequence(key, range);
  if (range.size() != 2) map.fail(key, "expected [min, max]");
  return InputRange{range[0], range[1]};
}

// The scalar keys of a correction (channel_correction.hpp), shared by reading and writing.
template <typename C>
auto correction_scalars(C& c) {
  return std::array<std::pair<const char*, decltype(&c.gain)>, 28>{{
      {"gain", &c.gain},
      {"offset", &c.offset},
      {"temperature_reference_degc", &c.temperature_reference_degc},
      {"temperature_gain_per_k", &c.temperature_gain_per_k},
      {"temperature_offset_per_k", &c.temperature_offset_per_k},
      {"temperature_drive_per_k", &c.temperature_drive_per_k},
      {"temperature_gain_per_k2", &c.temperature_gain_per_k2},
      {"temperature_drive_per_k2", &c.temperature_drive_per_k2},
      {"temperature_stress_per_k", &c.temperature_stress_per_k},
      {"temperature_stress_per_k2", &c.temperature_stress_per_k2},
      {"temperature_offset_per_k2", &c.temperature_offset_per_k2},
      {"drive_integral_per_s", &c.drive_integral_per_s},
      {"stress_gain_per_pa", &c.stress_gain_per_pa},
      {"stress_quadratic_per_pa2", &c.stress_quadratic_per_pa2},
      {"stress_drive_per_pa", &c.stress_drive_per_pa},
      {"stress_linear_per_pa", &c.stress_linear_per_pa},
      {"drive_quadratic", &c.drive_quadratic},
      {"drive_cubic", &c.drive_cubic},
      {"drive_linear", &c.drive_linear},
      {"sensed_quadratic", &c.sensed_quadratic},
      {"dynamics_frequency_hz", &c.dynamics_frequency_hz},
      {"dynamics_damping", &c.dynamics_damping},
      {"dynamics_direct", &c.dynamics_direct},
      {"dynamics2_frequency_hz", &c.dynamics2_frequency_hz},
      {"dynamics2_damping", &c.dynamics2_damping},
      {"dynamics2_share", &c.dynamics2_share},
      {"leakage_tau_s", &c.leakage_tau_s},
      {"delay_s", &c.delay_s},
  }};
}

// The play terms of a correction (hysteresis, asymmetric_hysteresis), written when present.
template <typename C>
auto correction_sequences(C& c) {
  return std::array<std::pair<const char*, decltype(&c.hysteresis_thresholds)>, 5>{{
      {"hysteresis_thresholds", &c.hysteresis_thresholds},
      {"hysteresis_weights", &c.hysteresis_weights},
      {"hinge_thresholds", &c.hinge_thresholds},
      {"hinge_levels", &c.hinge_levels},
      {"hinge_weights", &c.hinge_weights},
  }};
}

std::optional<ChannelCorrection> read_correction(YamlMap& corrections, std::string_view key) {
  std::optional<YamlMap> m = corrections.optional_map(key);
  if (!m) return std::nullopt;
  ChannelCorrection c;
  for (const auto& [name, field] : correction_scalars(c))
    m->read(name, *field);
  if (m->has("creep_eigenvalues")) m->read_sequence("creep_eigenvalues", c.creep_eigenvalues);
  if (m->has("creep_weights")) m->read_sequence("creep_weights", c.creep_weights);
  if (m->has("drive_creep_eigenvalues")) {
    m->read_sequence("drive_creep_eigenvalues", c.drive_creep_eigenvalues);
  }
  if (m->has("drive_creep_weights")) m->read_sequence("drive_creep_weights", c.drive_creep_weights);
  for (const auto& [name, field] : correction_sequences(c)) {
    if (m->has(name)) m->read_sequence(name, *field);
  }
  m->finish();
  return c;
}

// temperature: {reference_degc, sensor: {linear: [per_k, per_k2], loop: [...], coupling: [...]},
//               actuator: {...}, increments: [i_L, i_H] (optional)}
TemperatureCoefficients read_temperature(YamlMap& m) {
  TemperatureCoefficients t;
  t.reference_degc = m.required<double>("reference_degc");
  const auto side = [&m](std::string_view key, SideTemperature& out) {
    YamlMap s = m.map(key);
    const std::pair<const char*, TemperaturePolynomial*> polys[] = {
        {"linear", &out.linear}, {"loop", &out.loop}, {"coupling", &out.coupling}};
    for (const auto& [name, poly] : polys) {
      std::vector<double> v;
      s.read_sequence(name, v);
      if (v.size() != 2) s.fail(name, "expected [per_k, per_k2] (two numbers)");
      *poly = {v[0], v[1]};
    }
    s.finish();
  };
  side("sensor", t.sensor);
  side("actuator", t.actuator);
  if (m.has("increments")) {
    std::vector<double> v;
    m.read_sequence("increments", v);
    if (v.size() != 2) m.fail("increments", "expected [linear_per_k, loop_per_k] (two numbers)");
    t.increments = {v[0], v[1]};
  }
  m.finish();
  return t;
}

TransducerModel read_model(YamlMap root) {
  const int version = root.required<int>("selfsense_model");
  if (version < kOldestModelFormatVersion || version > kModelFormatVersion) {
    root.fail("selfsense_model", "format version " + std::to_string(version) +
                                     " is not supported (this build reads " +
                                     std::to_string(kOldestModelFormatVersion) + " to " +
                                     std::to_string(kModelFormatVersion) + ")");
  }
  // From version 2 the last key says the file is whole: a file cut short (copied over the old
  // one while the daemon reloads, a copy interrupted) lacks it, even where the cut leaves valid
  // YAML (a number cut to fewer digits, a sequence that lost its tail lines).
  if (version >= 2 || root.has("complete")) {
    if (!root.has("complete")) {
      root.fail("complete",
                "missing: a model file of format 2 ends with `complete: true`; this "
                "one ends before it (cut short, half-written?)");
    }
    if (!root.required<bool>("complete")) root.fail("complete", "must be true");
    if (root.last_key() != "complete") {
      root.fail("complete", "must be the file's last key (a model file ends with it)");
    }
  }
  TransducerModel model;
  const auto name = root.required<std::string>("structure");
  const std::optional<Structure> structure = parse_structure(name);
  if (!structure) root.fail("structure", "'" + name + "' is not one of " + structure_names());
  model.structure = *structure;
  model.sample_time = root.required<double>("sample_time_s");
  if (!(model.sample_time > 0.0)) root.fail("sample_time_s", "must be > 0");
  if (auto g = root.optional_map("geometry")) {
    const Geometry geo = read_geometry_fields(*g);
    std::string why;
    if (!geo.is_valid(&why)) throw io::YamlError(root.locate(why));
    model.geometry = geo;
  }
  if (auto r = root.optional_map("input_range")) {
    model.drive_range = read_range(*r, "drive");
    model.sensed_range = read_range(*r, "sensed");
    r->finish();
  }
  // A stress-hysteresis model may be completed by a plain side where its vectorial section has
  // none (models/stress_sides.hpp).
  if (model.structure == Structure::kStressHysteresis) {
    model.vectorial = read_vectorial(root, model.sample_time);
  }
  model.sensor = read_side(root, "sensor", model.sample_time);
  model.actuator = read_side(root, "actuator", model.sample_time);
  if (auto c = root.optional_map("corrections")) {
    model.sensed_correction = read_correction(*c, "sensed");
    model.strain_correction = read_correction(*c, "strain");
    c->finish();
  }
  if (auto t = root.optional_map("temperature")) {
    if (model.drive() != Drive::kField || !model.sensor || !model.actuator) {
      root.fail("temperature", "needs a field-driven model with both sides");
    }
    model.temperature = read_temperature(*t);
  }
  if (root.has("fit")) static_cast<void>(root.optional_map("fit"));  // notes only
  root.finish();
  std::string why;
  if (!model.is_valid(&why)) throw io::YamlError(root.locate(why));
  return model;
}

void emit_sequence(YAML::Emitter& out, const char* key, const std::vector<double>& values) {
  out << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (const double v : values)
    out << v;
  out << YAML::EndSeq;
}

void emit_temperature(YAML::Emitter& out, const TemperatureCoefficients& t) {
  out << YAML::Key << "temperature" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "reference_degc" << YAML::Value << t.reference_degc;
  const std::pair<const char*, const SideTemperature*> sides[] = {{"sensor", &t.sensor},
                                                                  {"actuator", &t.actuator}};
  for (const auto& [name, side] : sides) {
    out << YAML::Key << name << YAML::Value << YAML::BeginMap;
    emit_sequence(out, "linear", {side->linear.per_k, side->linear.per_k2});
    emit_sequence(out, "loop", {side->loop.per_k, side->loop.per_k2});
    emit_sequence(out, "coupling", {side->coupling.per_k, side->coupling.per_k2});
    out << YAML::EndMap;
  }
  if (t.increments.fitted()) {
    emit_sequence(out, "increments", {t.increments.linear_per_k, t.increments.loop_per_k});
  }
  out << YAML::EndMap;
}

void emit_side(YAML::Emitter& out, const char* key, const SideModel& side) {
  out << YAML::Key << key << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "coupling" << YAML::Value
      << (side.linear_gains.empty() ? 0.0 : side.linear_gains.front());
  out << YAML::Key << "offset" << YAML::Value << side.offset;
  if (side.quadratic != 0.0) out << YAML::Key << "quadratic" << YAML::Value << side.quadratic;
  emit_sequence(out, "history", side.history);
  const auto& h = side.op.hysteresis;
  out << YAML::Key << "hysteresis" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "linear_weight" << YAML::Value << h.linear_weight;
  emit_sequence(out, "thresholds", h.thresholds);
  emit_sequence(out, "weights", h.weights);
  out << YAML::EndMap;
  const auto& s = side.op.superposition;
  out << YAML::Key << "superposition" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "linear_weight" << YAML::Value << s.linear_weight;
  emit_sequence(out, "upper_thresholds", s.upper_thresholds);
  emit_sequence(out, "upper_weights", s.upper_weights);
  emit_sequence(out, "lower_thresholds", s.lower_thresholds);
  emit_sequence(out, "lower_weights", s.lower_weights);
  out << YAML::EndMap;
  const auto& c = side.op.creep;
  out << YAML::Key << "creep" << YAML::Value << YAML::BeginMap;
  emit_sequence(out, "thresholds", c.thresholds);
  emit_sequence(out, "eigenvalues", c.eigenvalues);
  emit_sequence(out, "weights", c.weights);
  out << YAML::EndMap;
  if (const auto& g = side.op.hinges; !g.empty()) {
    out << YAML::Key << "hinges" << YAML::Value << YAML::BeginMap;
    emit_sequence(out, "thresholds", g.thresholds);
    emit_sequence(out, "levels", g.levels);
    emit_sequence(out, "weights", g.weights);
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
}

void emit_vectorial(YAML::Emitter& out, const StressHysteresisModel& m) {
  out << YAML::Key << "vectorial" << YAML::Value << YAML::BeginMap;
  emit_sequence(out, "thresholds", m.basis.thresholds);
  emit_sequence(out, "history", m.history);
  if (!m.basis.eigenvalues.empty()) {
    out << YAML::Key << "creep" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "rows" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (const std::size_t r : m.basis.creep_rows)
      out << r;
    out << YAML::EndSeq;
    emit_sequence(out, "eigenvalues", m.basis.eigenvalues);
    out << YAML::EndMap;
  }
  emit_sequence(out, "stress_range", {m.stress_min, m.stress_max});
  for (const auto& [name, side] :
       {std::pair{"sensor", &m.sensor}, std::pair{"actuator", &m.actuator}}) {
    if (!*side) continue;
    out << YAML::Key << name << YAML::Value << YAML::BeginMap;
    emit_sequence(out, "base", (*side)->base);
    emit_sequence(out, "stress", (*side)->stress);
    out << YAML::Key << "linear" << YAML::Value << (*side)->linear;
    out << YAML::Key << "quadratic" << YAML::Value << (*side)->quadratic;
    out << YAML::Key << "offset" << YAML::Value << (*side)->offset;
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
}

void emit_correction(YAML::Emitter& out, const char* key, const ChannelCorrection& c) {
  out << YAML::Key << key << YAML::Value << YAML::BeginMap;
  // Terms a diagnosis did not add stay at their defaults and are left out.
  const ChannelCorrection defaults;
  const auto fallback = correction_scalars(defaults);
  const auto fields = correction_scalars(c);
  for (std::size_t i = 0; i < fields.size(); ++i) {
    if (*fields[i].second == *fallback[i].second) continue;
    out << YAML::Key << fields[i].first << YAML::Value << *fields[i].second;
  }
  if (!c.creep_eigenvalues.empty()) {
    emit_sequence(out, "creep_eigenvalues", c.creep_eigenvalues);
    emit_sequence(out, "creep_weights", c.creep_weights);
  }
  if (!c.drive_creep_eigenvalues.empty()) {
    emit_sequence(out, "drive_creep_eigenvalues", c.drive_creep_eigenvalues);
    emit_sequence(out, "drive_creep_weights", c.drive_creep_weights);
  }
  for (const auto& [name, field] : correction_sequences(c)) {
    if (!field->empty()) emit_sequence(out, name, *field);
  }
  out << YAML::EndMap;
}

}  // namespace

TransducerModel load_model(const std::filesystem::path& path) {
  return read_model(YamlMap::load_file(path));
}

TransducerModel model_from_string(const std::string& text, const std::string& source) {
  return read_model(YamlMap::from_string(text, source));
}

std::string model_to_string(const TransducerModel& model, const std::string& fit_notes) {
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  out << YAML::BeginMap;
  out << YAML::Key << "selfsense_model" << YAML::Value << kModelFormatVersion;
  out << YAML::Key << "structure" << YAML::Value << std::string(to_string(model.structure));
  out << YAML::Key << "sample_time_s" << YAML::Value << model.sample_time;
  if (model.geometry) {
    const Geometry& g = *model.geometry;
    out << YAML::Key << "geometry" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "layer_thickness_m" << YAML::Value << g.layer_thickness;
    out << YAML::Key << "electrode_area_m2" << YAML::Value << g.electrode_area;
    out << YAML::Key << "layers" << YAML::Value << g.layers;
    out << YAML::Key << "active_length_m" << YAML::Value << g.active_length;
    out << YAML::Key << "cross_section_m2" << YAML::Value << g.cross_section;
    out << YAML::EndMap;
  }
  if (model.drive_range || model.sensed_range) {
    out << YAML::Key << "input_range" << YAML::Value << YAML::BeginMap;
    if (model.drive_range) {
      emit_sequence(out, "drive", {model.drive_range->min, model.drive_range->max});
    }
    if (model.sensed_range) {
      emit_sequence(out, "sensed", {model.sensed_range->min, model.sensed_range->max});
    }
    out << YAML::EndMap;
  }
  if (model.vectorial) emit_vectorial(out, *model.vectorial);
  if (model.sensor) emit_side(out, "sensor", *model.sensor);
  if (model.actuator) emit_side(out, "actuator", *model.actuator);
  if (model.sensed_correction || model.strain_correction) {
    out << YAML::Key << "corrections" << YAML::Value << YAML::BeginMap;
    if (model.sensed_correction) emit_correction(out, "sensed", *model.sensed_correction);
    if (model.strain_correction) emit_correction(out, "strain", *model.strain_correction);
    out << YAML::EndMap;
  }
  if (model.temperature) emit_temperature(out, *model.temperature);
  if (!fit_notes.empty()) out << YAML::Key << "fit" << YAML::Value << YAML::Load(fit_notes);
  out << YAML::Key << "complete" << YAML::Value << true;  // last: the file is whole
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

// Written beside the target and renamed over it: a reader (the daemon reloading) sees the old
// file or the new one, never a part of it; fsync first, so a power cut cannot leave the new
// name on an empty file.
void save_model(const TransducerModel& model, const std::filesystem::path& path,
                const std::string& fit_notes) {
  const std::string text = model_to_string(model, fit_notes);
  const std::filesystem::path parent = path.has_parent_path() ? path.parent_path() : ".";
  std::string temp_name = path.filename().string();  // appended, not "." + ...: gcc 12 -Wrestrict
  temp_name.insert(0, 1, '.');
  temp_name.append(".tmp-").append(std::to_string(::getpid()));
  const std::filesystem::path temp = parent / temp_name;
  const auto fail = [&](const char* what) {
    const int error = errno;
    static_cast<void>(::unlink(temp.c_str()));
    throw std::runtime_error(path.string() + ": cannot write the model (" + what + ": " +
                             base::errno_text(error) + ")");
  };
  const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) fail("open");
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      static_cast<void>(::close(fd));
      fail("write");
    }
    done += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0) {
    static_cast<void>(::close(fd));
    fail("fsync");
  }
  if (::close(fd) != 0) fail("close");
  if (::rename(temp.c_str(), path.c_str()) != 0) fail("rename");
}

}  // namespace selfsense::models
