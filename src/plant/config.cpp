#include "selfsense/plant/config.hpp"

#include <cmath>
#include <numbers>
#include <sstream>

#include "checker.hpp"

namespace selfsense::plant {

namespace {

using detail::Checker;

std::string indexed(const std::string& path, std::size_t i) {
  return path + "[" + std::to_string(i) + "]";
}

void check_channel(Checker& c, const std::string& path, const ChannelConfig& ch) {
  c.require(ch.delay_samples >= 0 && ch.delay_samples <= kMaxDelaySamples, path + ".delay_samples",
            ch.delay_samples, "must be in [0, " + std::to_string(kMaxDelaySamples) + "]");
  c.non_negative(path + ".noise_std", ch.noise_std);
  c.require(ch.adc.bits >= 1 && ch.adc.bits <= 24, path + ".adc.bits", ch.adc.bits,
            "must be in [1, 24]");
  c.finite(path + ".adc.min", ch.adc.min);
  c.require(std::isfinite(ch.adc.max) && ch.adc.max > ch.adc.min, path + ".adc.max", ch.adc.max,
            "must be above adc.min");
}

}  // namespace

bool PlantConfig::is_valid(std::string* why) const {
  Checker c{why, "plant."};
  c.positive("sample_rate_hz", sample_rate_hz);
  const double nyquist = 0.5 * sample_rate_hz;

  c.require(geometry.layers >= 1, "geometry.layers", geometry.layers, "must be >= 1");
  c.positive("geometry.layer_thickness_m", geometry.layer_thickness_m);
  c.positive("geometry.electrode_area_m2", geometry.electrode_area_m2);
  c.positive("geometry.cross_section_m2", geometry.cross_section_m2);

  c.require(std::isfinite(material.permittivity_f_per_m) && material.permittivity_f_per_m > 0.0,
            "material.permittivity_f_per_m", material.permittivity_f_per_m,
            "must be > 0 (the stack capacitance n eps A / h must be positive)");
  c.positive("material.d33_m_per_v", material.d33_m_per_v);
  c.positive("material.compliance_m2_per_n", material.compliance_m2_per_n);

  const HysteresisConfig& h = hysteresis;
  c.finite("hysteresis.field_min_v_per_m", h.field_min_v_per_m);
  c.require(std::isfinite(h.field_max_v_per_m) && h.field_max_v_per_m > h.field_min_v_per_m,
            "hysteresis.field_max_v_per_m", h.field_max_v_per_m, "must be above field_min_v_per_m");
  c.require(h.levels >= 8 && h.levels <= 1024, "hysteresis.levels", h.levels,
            "must be in [8, 1024]");
  c.non_negative("hysteresis.width_center_v_per_m", h.width_center_v_per_m);
  c.positive("hysteresis.width_sigma_v_per_m", h.width_sigma_v_per_m);
  c.finite("hysteresis.bias_center_v_per_m", h.bias_center_v_per_m);
  c.positive("hysteresis.bias_sigma_v_per_m", h.bias_sigma_v_per_m);
  c.require(std::isfinite(h.asymmetry) && std::abs(h.asymmetry) < 1.0, "hysteresis.asymmetry",
            h.asymmetry, "must be in (-1, 1)");
  c.non_negative("hysteresis.d_amplitude_c_per_m2", h.d_amplitude_c_per_m2);
  c.non_negative("hysteresis.s_amplitude", h.s_amplitude);

  c.require(creep.tau_s.size() <= kMaxCreepElements, "creep.tau_s", creep.tau_s.size(),
            "at most " + std::to_string(kMaxCreepElements) + " elements");
  c.require(creep.s_weights.size() == creep.tau_s.size(), "creep.s_weights", creep.s_weights.size(),
            "needs one weight per tau_s entry");
  c.require(creep.d_weights.size() == creep.tau_s.size(), "creep.d_weights", creep.d_weights.size(),
            "needs one weight per tau_s entry");
  for (std::size_t i = 0; i < creep.tau_s.size(); ++i) {
    c.positive(indexed("creep.tau_s", i), creep.tau_s[i]);
  }
  for (std::size_t i = 0; i < creep.s_weights.size(); ++i) {
    c.non_negative(indexed("creep.s_weights", i), creep.s_weights[i]);
  }
  for (std::size_t i = 0; i < creep.d_weights.size(); ++i) {
    c.non_negative(indexed("creep.d_weights", i), creep.d_weights[i]);
  }

  const PermittivityConfig& pe = permittivity;
  c.positive("permittivity.reference_field_v_per_m", pe.reference_field_v_per_m);
  c.finite("permittivity.linear_coefficient", pe.linear_coefficient);
  c.finite("electrostriction.q_m4_per_c2", electrostriction.q_m4_per_c2);
  c.finite("permittivity.quadratic_coefficient", pe.quadratic_coefficient);

  c.finite("stress.d_coefficient_per_pa", stress.d_coefficient_per_pa);
  c.finite("stress.hysteresis_coefficient_per_pa", stress.hysteresis_coefficient_per_pa);
  c.finite("stress.permittivity_coefficient_per_pa", stress.permittivity_coefficient_per_pa);

  c.finite("temperature.reference_degc", temperature.reference_degc);
  c.finite("temperature.permittivity_coefficient_per_k",
           temperature.permittivity_coefficient_per_k);
  c.finite("temperature.d_coefficient_per_k", temperature.d_coefficient_per_k);
  c.finite("temperature.hysteresis_coefficient_per_k", temperature.hysteresis_coefficient_per_k);
  c.finite("temperature.compliance_coefficient_per_k", temperature.compliance_coefficient_per_k);

  c.non_negative("aging.polarisation_loss_per_h", aging.polarisation_loss_per_h);
  c.non_negative("aging.capacitance_loss_per_h", aging.capacitance_loss_per_h);
  c.non_negative("aging.leakage_resistivity_ohm_m", aging.leakage_resistivity_ohm_m);
  c.non_negative("aging.leakage_growth_per_h", aging.leakage_growth_per_h);
  c.non_negative("aging.start_s", aging.start_s);
  c.non_negative("heating.thermal_resistance_k_per_w", heating.thermal_resistance_k_per_w);
  c.positive("heating.time_constant_s", heating.time_constant_s);

  c.positive("mechanics.resonance_hz", mechanics.resonance_hz);
  if (mechanics.enabled) {
    std::ostringstream constraint;
    constraint << "is above the Nyquist frequency " << nyquist << " of sample_rate_hz";
    c.require(mechanics.resonance_hz < nyquist, "mechanics.resonance_hz", mechanics.resonance_hz,
              constraint.str());
  }
  c.non_negative("mechanics.damping_ratio", mechanics.damping_ratio);
  c.non_negative("mechanics.load_stiffness_n_per_m", mechanics.load_stiffness_n_per_m);
  c.finite("mechanics.load_force_n", mechanics.load_force_n);

  c.positive("charge_amplifier.leakage_tau_s", charge_amplifier.leakage_tau_s);
  c.finite("charge_amplifier.offset_c", charge_amplifier.offset_c);
  c.finite("charge_amplifier.drift_c_per_s", charge_amplifier.drift_c_per_s);
  c.non_negative("charge_amplifier.random_walk_c_per_sqrt_s",
                 charge_amplifier.random_walk_c_per_sqrt_s);

  // The plant starts at 0 V and a fault discharges the stack towards 0 V.
  c.require(std::isfinite(amplifier.voltage_min_v) && amplifier.voltage_min_v <= 0.0,
            "amplifier.voltage_min_v", amplifier.voltage_min_v, "must be a finite number <= 0");
  c.require(std::isfinite(amplifier.voltage_max_v) &&
                amplifier.voltage_max_v > amplifier.voltage_min_v && amplifier.voltage_max_v >= 0.0,
            "amplifier.voltage_max_v", amplifier.voltage_max_v,
            "must be above voltage_min_v and >= 0");
  c.positive("amplifier.slew_rate_v_per_s", amplifier.slew_rate_v_per_s);
  c.positive("amplifier.current_limit_a", amplifier.current_limit_a);

  if (c.ok() && pe.enabled) {
    // D = eps E (1 + k1 x + k2 x^2) must rise with E over the amplifier's range (x = E / E_ref).
    const double lo =
        amplifier.voltage_min_v / geometry.layer_thickness_m / pe.reference_field_v_per_m;
    const double hi =
        amplifier.voltage_max_v / geometry.layer_thickness_m / pe.reference_field_v_per_m;
    bool monotone = true;
    for (int i = 0; i <= 200; ++i) {
      const double x = lo + (hi - lo) * i / 200.0;
      monotone =
          monotone &&
          1.0 + 2.0 * pe.linear_coefficient * x + 3.0 * pe.quadratic_coefficient * x * x > 0.0;
    }
    c.require(monotone, "permittivity.quadratic_coefficient", pe.quadratic_coefficient,
              "D(E) must rise with E over the amplifier's voltage range");
  }

  check_channel(c, "sensors.e", sensors.e);
  check_channel(c, "sensors.d", sensors.d);

  c.require(faults.size() <= kMaxScheduledFaults, "faults", faults.size(),
            "at most " + std::to_string(kMaxScheduledFaults) + " entries");
  for (std::size_t i = 0; i < faults.size(); ++i) {
    const FaultEntry& f = faults[i];
    c.non_negative(indexed("faults", i) + ".start_s", f.start_s);
    c.non_negative(indexed("faults", i) + ".duration_s", f.duration_s);
    c.non_negative(indexed("faults", i) + ".late_by_s", f.late_by_s);
    c.require(f.kind != FaultKind::late_sample || f.late_by_s > 0.0,
              indexed("faults", i) + ".late_by_s", f.late_by_s,
              "a late_sample needs late_by_s > 0");
  }
  return c.ok();
}

const char* to_string(FaultKind kind) noexcept {
  switch (kind) {
    case FaultKind::stuck_adc:
      return "stuck_adc";
    case FaultKind::nan_sample:
      return "nan_sample";
    case FaultKind::out_of_range:
      return "out_of_range";
    case FaultKind::missed_data_ready:
      return "missed_data_ready";
    case FaultKind::late_sample:
      return "late_sample";
    case FaultKind::amplifier_fault:
      return "amplifier_fault";
    case FaultKind::sensor_disconnect:
      return "sensor_disconnect";
  }
  return "?";
}

const char* to_string(Channel channel) noexcept {
  switch (channel) {
    case Channel::e:
      return "e";
    case Channel::d:
      return "d";
    case Channel::both:
      return "both";
  }
  return "?";
}

Derived derive(const PlantConfig& config) noexcept {
  const GeometryConfig& g = config.geometry;
  const MaterialConfig& m = config.material;
  Derived d{};
  d.length_m = g.layers * g.layer_thickness_m;
  d.capacitance_f = g.layers * m.permittivity_f_per_m * g.electrode_area_m2 / g.layer_thickness_m;
  d.stack_stiffness_n_per_m = g.cross_section_m2 / (m.compliance_m2_per_n * d.length_m);
  d.free_stroke_m = m.d33_m_per_v * 2.0e6 * d.length_m;
  d.blocking_force_n = d.stack_stiffness_n_per_m * d.free_stroke_m;
  if (config.mechanics.enabled) {
    const double w = 2.0 * std::numbers::pi * config.mechanics.resonance_hz;
    d.effective_mass_kg =
        (d.stack_stiffness_n_per_m + config.mechanics.load_stiffness_n_per_m) / (w * w);
  }
  return d;
}

}  // namespace selfsense::plant
