#include "selfsense/plant/plant.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace selfsense::plant {

namespace {

// A coefficient scale 1 + k * delta, kept positive so no effect can flip a sign.
double scale(double k, double delta) noexcept {
  return std::max(1.0 + k * delta, 0.05);
}

PlantConfig validated(const PlantConfig& config) {
  std::string why;
  if (!config.is_valid(&why)) throw std::invalid_argument{why};
  return config;
}

}  // namespace

Plant::Plant(const PlantConfig& config)
    : config_{validated(config)}, derived_{derive(config_)}, ts_{1.0 / config_.sample_rate_hz} {
  if (config_.hysteresis.enabled) everett_ = std::make_unique<EverettTable>(config_.hysteresis);
  reset();
}

double Plant::capacitance_linear(double e) const noexcept {
  double eps = config_.material.permittivity_f_per_m;
  const PermittivityConfig& pe = config_.permittivity;
  if (pe.enabled) {
    // Incremental: d(eps(E) E)/dE.
    const double x = e / pe.reference_field_v_per_m;
    eps *= 1.0 + 2.0 * pe.linear_coefficient * x + 3.0 * pe.quadratic_coefficient * x * x;
  }
  return derived_.capacitance_f * eps / config_.material.permittivity_f_per_m;
}

void Plant::reset() {
  const PlantConfig& c = config_;
  State s{};
  s.random = Random{c.seed};
  if (c.creep.enabled) {
    s.creep_s = CreepBank{c.creep.tau_s, c.creep.s_weights, ts_};
    s.creep_d = CreepBank{c.creep.tau_s, c.creep.d_weights, ts_};
  }
  s.creep_s.reset(0.0);
  s.creep_d.reset(0.0);
  if (c.mechanics.enabled) {
    s.mechanics = Mechanics{c.mechanics.resonance_hz, c.mechanics.damping_ratio, ts_};
  }
  s.amplifier = Amplifier{c.amplifier, ts_};
  s.amplifier.reset(0.0);
  s.charge_amplifier = ChargeAmplifier{c.charge_amplifier, ts_};
  s.charge_amplifier.reset(0.0);
  s.channel_e = SensorChannel{c.sensors.e};
  s.channel_e.reset(0.0);
  s.channel_d = SensorChannel{c.sensors.d};
  s.channel_d.reset(0.0);
  for (const FaultEntry& f : c.faults) {
    const auto start = std::llround(f.start_s * c.sample_rate_hz);
    const auto duration = std::max<std::int64_t>(1, std::llround(f.duration_s * c.sample_rate_hz));
    s.faults.add(ActiveFault{f.kind, f.channel, start, start + duration, f.late_by_s});
  }
  if (everett_) {
    s.preisach.reset(*everett_, 0.0);
    s.p0 = s.preisach.output();
  }
  // Static equilibrium under the load at E = 0 (S_free = 0).
  const double k_s = derived_.stack_stiffness_n_per_m;
  const double x0 = c.mechanics.load_force_n / (k_s + c.mechanics.load_stiffness_n_per_m);
  s.mechanics.reset(x0);
  s.t_prev_pa = x0 / derived_.length_m / c.material.compliance_m2_per_n;
  const double d_scale = c.stress.enabled ? scale(c.stress.d_coefficient_per_pa, s.t_prev_pa) : 1.0;
  s.d0 = c.material.d33_m_per_v * d_scale * s.t_prev_pa;
  s.capacitance_est_f = capacitance_linear(0.0);
  state_ = s;
}

bool Plant::inject(FaultKind kind, Channel channel, std::int64_t start_sample,
                   std::int64_t duration_samples, double late_by_s) noexcept {
  return state_.faults.add(ActiveFault{kind, channel, start_sample,
                                       start_sample + std::max<std::int64_t>(1, duration_samples),
                                       late_by_s});
}

StepOutput Plant::step(const StepInput& input) noexcept {
  const PlantConfig& c = config_;
  State& s = state_;
  const FaultEffects fx = s.faults.at(s.sample);
  std::uint32_t flags = kStatusOk;

  // Coefficient scales: temperature from the input, stress from the previous sample.
  double eps_scale = 1.0;
  double d_scale = 1.0;
  double hyst_scale = 1.0;
  double compliance_scale = 1.0;
  if (c.temperature.enabled) {
    const double dt = input.temp_degc - c.temperature.reference_degc;
    eps_scale *= scale(c.temperature.permittivity_coefficient_per_k, dt);
    d_scale *= scale(c.temperature.d_coefficient_per_k, dt);
    hyst_scale *= scale(c.temperature.hysteresis_coefficient_per_k, dt);
    compliance_scale *= scale(c.temperature.compliance_coefficient_per_k, dt);
  }
  if (c.stress.enabled) {
    eps_scale *= scale(c.stress.permittivity_coefficient_per_pa, s.t_prev_pa);
    d_scale *= scale(c.stress.d_coefficient_per_pa, s.t_prev_pa);
    hyst_scale *= scale(c.stress.hysteresis_coefficient_per_pa, s.t_prev_pa);
  }

  const double h = c.geometry.layer_thickness_m;
  const double u =
      s.amplifier.update(input.e_cmd_v_per_m * h, s.capacitance_est_f, fx.amplifier_fault, &flags);
  const double e = u / h;

  double dp = 0.0;
  if (everett_) dp = s.preisach.update(*everett_, e) - s.p0;

  const double d_eff = c.material.d33_m_per_v * d_scale;
  double eps_eff = c.material.permittivity_f_per_m * eps_scale;
  if (c.permittivity.enabled) {
    const double x = e / c.permittivity.reference_field_v_per_m;
    eps_eff *=
        1.0 + c.permittivity.linear_coefficient * x + c.permittivity.quadratic_coefficient * x * x;
  }
  const double s_inst = d_eff * e + c.hysteresis.s_amplitude * hyst_scale * dp;
  const double d_inst = eps_eff * e + c.hysteresis.d_amplitude_c_per_m2 * hyst_scale * dp;
  const double s_free = s_inst + s.creep_s.update(s_inst);
  const double d_free = d_inst + s.creep_d.update(d_inst);

  const double compliance = c.material.compliance_m2_per_n * compliance_scale;
  const double length = derived_.length_m;
  const double k_s = c.geometry.cross_section_m2 / (compliance * length);
  const double force = c.mechanics.load_force_n + input.force_n;
  const double x_eq = (k_s * length * s_free + force) / (k_s + c.mechanics.load_stiffness_n_per_m);
  const double x = c.mechanics.enabled ? s.mechanics.update(x_eq) : x_eq;
  const double strain = x / length;
  const double stress = (strain - s_free) / compliance;
  const double d = d_free + d_eff * stress;

  const double electrode_area = c.geometry.layers * c.geometry.electrode_area_m2;
  const double q = electrode_area * (d - s.d0);
  const double q_m = s.charge_amplifier.update(q, s.random);

  const double du = u - s.u_prev_v;
  if (std::abs(du) > 1e-3) {
    const double c_lin = capacitance_linear(e);
    s.capacitance_est_f = std::clamp((q - s.q_prev_c) / du, c_lin, 10.0 * c_lin);
  }
  s.u_prev_v = u;
  s.q_prev_c = q;
  s.t_prev_pa = stress;

  // Every channel is sampled every time, so faults never shift the random sequence.
  double e_meas = s.channel_e.measure(fx.disconnect_e ? 0.0 : e, s.random, &flags);
  double d_meas =
      s.channel_d.measure(fx.disconnect_d ? 0.0 : q_m / electrode_area, s.random, &flags);
  if (fx.disconnect_e || fx.disconnect_d) flags |= kSensorDisconnect;
  if (fx.stuck_e) e_meas = s.last.e_meas_v_per_m;
  if (fx.stuck_d) d_meas = s.last.d_meas_c_per_m2;
  if (fx.stuck_e || fx.stuck_d) flags |= kStuckAdc;
  if (fx.out_of_range_e) e_meas = s.channel_e.out_of_range_value();
  if (fx.out_of_range_d) d_meas = s.channel_d.out_of_range_value();
  if (fx.out_of_range_e || fx.out_of_range_d) flags |= kOutOfRange;
  if (fx.nan_e) e_meas = std::numeric_limits<double>::quiet_NaN();
  if (fx.nan_d) d_meas = std::numeric_limits<double>::quiet_NaN();
  if (fx.nan_e || fx.nan_d) flags |= kNanSample;
  if (fx.missed_data_ready) {
    e_meas = s.last.e_meas_v_per_m;
    d_meas = s.last.d_meas_c_per_m2;
    flags |= kMissedDataReady;
  }
  if (fx.late_by_s > 0.0) flags |= kLateSample;
  if (fx.amplifier_fault) flags |= kAmplifierFault;

  StepOutput out{};
  out.t_s = static_cast<double>(s.sample) * ts_;
  out.e_meas_v_per_m = e_meas;
  out.d_meas_c_per_m2 = d_meas;
  out.e_v_per_m = e;
  out.d_c_per_m2 = d - s.d0;
  out.s = strain;
  out.t_pa = stress;
  out.u_v = u;
  out.q_c = q_m;
  out.x_m = x;
  out.f_n = stress * c.geometry.cross_section_m2;
  out.temp_degc = input.temp_degc;
  out.polarisation = dp + s.p0;
  out.latency_s = fx.late_by_s;
  out.status = flags;
  s.last = out;
  ++s.sample;
  return out;
}

void Plant::run(std::span<const StepInput> in, std::span<StepOutput> out) noexcept {
  const std::size_t n = std::min(in.size(), out.size());
  for (std::size_t i = 0; i < n; ++i)
    out[i] = step(in[i]);
}

std::vector<StepOutput> simulate(const PlantConfig& config, std::span<const StepInput> inputs) {
  Plant plant{config};
  std::vector<StepOutput> out(inputs.size());
  plant.run(inputs, out);
  return out;
}

}  // namespace selfsense::plant
