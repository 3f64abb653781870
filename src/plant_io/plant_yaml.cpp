#include "selfsense/plant_io/plant_yaml.hpp"

#include <array>
#include <utility>

#include "selfsense/io/yaml_map.hpp"

namespace selfsense::plant {

namespace {

using io::YamlMap;

void read_channel(YamlMap map, ChannelConfig& ch) {
  map.read("delay_samples", ch.delay_samples);
  map.read("noise_std", ch.noise_std);
  if (auto adc = map.optional_map("adc")) {
    adc->read("enabled", ch.adc.enabled);
    adc->read("bits", ch.adc.bits);
    adc->read("min", ch.adc.min);
    adc->read("max", ch.adc.max);
    adc->finish();
  }
  map.finish();
}

template <typename Enum, std::size_t N>
Enum parse_enum(YamlMap& map, std::string_view key, const std::array<Enum, N>& values,
                Enum fallback) {
  std::string text;
  map.read(key, text);
  if (text.empty() && !map.has(key)) return fallback;
  std::string names;
  for (const Enum v : values) {
    if (text == to_string(v)) return v;
    names += names.empty() ? "" : ", ";
    names += to_string(v);
  }
  map.fail(key, "'" + text + "' is not one of: " + names);
}

FaultEntry read_fault(YamlMap map) {
  FaultEntry f{};
  if (!map.has("kind")) map.fail("kind", "required key is missing");
  f.kind =
      parse_enum(map, "kind",
                 std::array{FaultKind::stuck_adc, FaultKind::nan_sample, FaultKind::out_of_range,
                            FaultKind::missed_data_ready, FaultKind::late_sample,
                            FaultKind::amplifier_fault, FaultKind::sensor_disconnect},
                 FaultKind::nan_sample);
  f.channel =
      parse_enum(map, "channel", std::array{Channel::e, Channel::d, Channel::both}, Channel::d);
  map.read("start_s", f.start_s);
  map.read("duration_s", f.duration_s);
  map.read("late_by_s", f.late_by_s);
  map.finish();
  return f;
}

void read_plant(YamlMap p, PlantConfig& c) {
  p.read("sample_rate_hz", c.sample_rate_hz);
  p.read("seed", c.seed);
  if (auto m = p.optional_map("geometry")) {
    m->read("layers", c.geometry.layers);
    m->read("layer_thickness_m", c.geometry.layer_thickness_m);
    m->read("electrode_area_m2", c.geometry.electrode_area_m2);
    m->read("cross_section_m2", c.geometry.cross_section_m2);
    m->finish();
  }
  if (auto m = p.optional_map("material")) {
    m->read("permittivity_f_per_m", c.material.permittivity_f_per_m);
    m->read("d33_m_per_v", c.material.d33_m_per_v);
    m->read("compliance_m2_per_n", c.material.compliance_m2_per_n);
    m->finish();
  }
  if (auto m = p.optional_map("hysteresis")) {
    HysteresisConfig& h = c.hysteresis;
    m->read("enabled", h.enabled);
    m->read("field_min_v_per_m", h.field_min_v_per_m);
    m->read("field_max_v_per_m", h.field_max_v_per_m);
    m->read("levels", h.levels);
    m->read("width_center_v_per_m", h.width_center_v_per_m);
    m->read("width_sigma_v_per_m", h.width_sigma_v_per_m);
    m->read("bias_center_v_per_m", h.bias_center_v_per_m);
    m->read("bias_sigma_v_per_m", h.bias_sigma_v_per_m);
    m->read("asymmetry", h.asymmetry);
    m->read("d_amplitude_c_per_m2", h.d_amplitude_c_per_m2);
    m->read("s_amplitude", h.s_amplitude);
    m->finish();
  }
  if (auto m = p.optional_map("creep")) {
    m->read("enabled", c.creep.enabled);
    m->read_sequence("tau_s", c.creep.tau_s);
    m->read_sequence("s_weights", c.creep.s_weights);
    m->read_sequence("d_weights", c.creep.d_weights);
    m->finish();
  }
  if (auto m = p.optional_map("permittivity")) {
    m->read("enabled", c.permittivity.enabled);
    m->read("linear_coefficient", c.permittivity.linear_coefficient);
    m->read("quadratic_coefficient", c.permittivity.quadratic_coefficient);
    m->read("reference_field_v_per_m", c.permittivity.reference_field_v_per_m);
    m->finish();
  }
  if (auto m = p.optional_map("electrostriction")) {
    m->read("enabled", c.electrostriction.enabled);
    m->read("q_m4_per_c2", c.electrostriction.q_m4_per_c2);
    m->finish();
  }
  if (auto m = p.optional_map("stress")) {
    m->read("enabled", c.stress.enabled);
    m->read("d_coefficient_per_pa", c.stress.d_coefficient_per_pa);
    m->read("hysteresis_coefficient_per_pa", c.stress.hysteresis_coefficient_per_pa);
    m->read("permittivity_coefficient_per_pa", c.stress.permittivity_coefficient_per_pa);
    m->finish();
  }
  if (auto m = p.optional_map("temperature")) {
    TemperatureConfig& t = c.temperature;
    m->read("enabled", t.enabled);
    m->read("reference_degc", t.reference_degc);
    m->read("permittivity_coefficient_per_k", t.permittivity_coefficient_per_k);
    m->read("d_coefficient_per_k", t.d_coefficient_per_k);
    m->read("hysteresis_coefficient_per_k", t.hysteresis_coefficient_per_k);
    m->read("compliance_coefficient_per_k", t.compliance_coefficient_per_k);
    m->finish();
  }
  if (auto m = p.optional_map("aging")) {
    AgingConfig& a = c.aging;
    m->read("enabled", a.enabled);
    m->read("polarisation_loss_per_h", a.polarisation_loss_per_h);
    m->read("capacitance_loss_per_h", a.capacitance_loss_per_h);
    m->read("leakage_resistivity_ohm_m", a.leakage_resistivity_ohm_m);
    m->read("leakage_growth_per_h", a.leakage_growth_per_h);
    m->read("start_s", a.start_s);
    m->finish();
  }
  if (auto m = p.optional_map("heating")) {
    HeatingConfig& h = c.heating;
    m->read("enabled", h.enabled);
    m->read("thermal_resistance_k_per_w", h.thermal_resistance_k_per_w);
    m->read("time_constant_s", h.time_constant_s);
    m->finish();
  }
  if (auto m = p.optional_map("mechanics")) {
    m->read("enabled", c.mechanics.enabled);
    m->read("resonance_hz", c.mechanics.resonance_hz);
    m->read("damping_ratio", c.mechanics.damping_ratio);
    m->read("load_stiffness_n_per_m", c.mechanics.load_stiffness_n_per_m);
    m->read("load_force_n", c.mechanics.load_force_n);
    m->finish();
  }
  if (auto m = p.optional_map("charge_amplifier")) {
    ChargeAmplifierConfig& q = c.charge_amplifier;
    m->read("leakage_enabled", q.leakage_enabled);
    m->read("leakage_tau_s", q.leakage_tau_s);
    m->read("drift_enabled", q.drift_enabled);
    m->read("offset_c", q.offset_c);
    m->read("drift_c_per_s", q.drift_c_per_s);
    m->read("random_walk_c_per_sqrt_s", q.random_walk_c_per_sqrt_s);
    m->finish();
  }
  if (auto m = p.optional_map("amplifier")) {
    m->read("enabled", c.amplifier.enabled);
    m->read("voltage_min_v", c.amplifier.voltage_min_v);
    m->read("voltage_max_v", c.amplifier.voltage_max_v);
    m->read("slew_rate_v_per_s", c.amplifier.slew_rate_v_per_s);
    m->read("current_limit_a", c.amplifier.current_limit_a);
    m->finish();
  }
  if (auto m = p.optional_map("sensors")) {
    if (auto e = m->optional_map("e")) read_channel(std::move(*e), c.sensors.e);
    if (auto d = m->optional_map("d")) read_channel(std::move(*d), c.sensors.d);
    m->finish();
  }
  c.faults.clear();
  for (YamlMap& f : p.maps("faults"))
    c.faults.push_back(read_fault(std::move(f)));
  p.finish();
}

void read_excitation(YamlMap x, ExcitationConfig& c) {
  if (auto m = x.optional_map("steps")) {
    m->read_sequence("levels_v_per_m", c.steps.levels_v_per_m);
    m->read("hold_s", c.steps.hold_s);
    m->finish();
  }
  if (auto m = x.optional_map("sines")) {
    m->read_sequence("amplitudes_v_per_m", c.sines.amplitudes_v_per_m);
    m->read_sequence("frequencies_hz", c.sines.frequencies_hz);
    m->read("offset_v_per_m", c.sines.offset_v_per_m);
    m->read("cycles", c.sines.cycles);
    m->read("ramp_s", c.sines.ramp_s);
    m->finish();
  }
  if (auto m = x.optional_map("decaying")) {
    m->read("amplitude_v_per_m", c.decaying.amplitude_v_per_m);
    m->read("offset_v_per_m", c.decaying.offset_v_per_m);
    m->read("frequency_hz", c.decaying.frequency_hz);
    m->read("decay_per_cycle", c.decaying.decay_per_cycle);
    m->read("cycles", c.decaying.cycles);
    m->read("ramp_s", c.decaying.ramp_s);
    m->finish();
  }
  if (auto m = x.optional_map("noise")) {
    m->read("duration_s", c.noise.duration_s);
    m->read("cutoff_hz", c.noise.cutoff_hz);
    m->read("std_v_per_m", c.noise.std_v_per_m);
    m->read("offset_v_per_m", c.noise.offset_v_per_m);
    m->read("min_v_per_m", c.noise.min_v_per_m);
    m->read("max_v_per_m", c.noise.max_v_per_m);
    m->finish();
  }
  if (auto m = x.optional_map("loops")) {
    m->read("duration_s", c.loops.duration_s);
    m->read("min_v_per_m", c.loops.min_v_per_m);
    m->read("max_v_per_m", c.loops.max_v_per_m);
    m->read("rate_min_v_per_m_s", c.loops.rate_min_v_per_m_s);
    m->read("rate_max_v_per_m_s", c.loops.rate_max_v_per_m_s);
    m->read("hold_max_s", c.loops.hold_max_s);
    m->finish();
  }
  if (auto m = x.optional_map("load")) {
    m->read("offset_n", c.load.offset_n);
    m->read("amplitude_n", c.load.amplitude_n);
    m->read("frequency_hz", c.load.frequency_hz);
    m->finish();
  }
  if (auto m = x.optional_map("temperature")) {
    m->read("start_degc", c.temperature.start_degc);
    m->read("end_degc", c.temperature.end_degc);
    m->finish();
  }
  x.finish();
}

PlantFile read_file(YamlMap root) {
  PlantFile file{};
  read_plant(root.map("plant"), file.plant);
  if (auto x = root.optional_map("excitation")) read_excitation(std::move(*x), file.excitation);
  root.finish();
  std::string why;
  if (!file.plant.is_valid(&why)) throw io::YamlError{root.locate(why)};
  if (!file.excitation.is_valid(&why)) throw io::YamlError{root.locate(why)};
  return file;
}

}  // namespace

PlantFile load_plant_file(const std::filesystem::path& path) {
  return read_file(YamlMap::load_file(path));
}

PlantFile parse_plant_yaml(const std::string& text, const std::string& source) {
  return read_file(YamlMap::from_string(text, source));
}

}  // namespace selfsense::plant
