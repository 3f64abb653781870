#include "selfsense/plant/plant.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace selfsense::plant {

namespace {

// A coefficient scale 1 + k * delta, kept positive so no effect can flip a sign.
double scale(double k, double delta) noexcept {
  return std::max(1.0 + k * delta, 0.05);
}

// Relative scales of the material coefficients at one temperature and stress.
struct Scales {
  double eps{1.0};
  double d{1.0};
  double hysteresis{1.0};
  double compliance{1.0};
};

Scales temperature_scales(const TemperatureConfig& t, double temp_degc) noexcept {
  if (!t.enabled) return Scales{};
  const double dt = temp_degc - t.reference_degc;
  return Scales{scale(t.permittivity_coefficient_per_k, dt), scale(t.d_coefficient_per_k, dt),
                scale(t.hysteresis_coefficient_per_k, dt),
                scale(t.compliance_coefficient_per_k, dt)};
}

// The aging scales at the plant's time t (AgingConfig in config.hpp).
Scales with_aging(Scales s, const AgingConfig& a, double t_s) noexcept {
  if (!a.enabled) return s;
  const double hours = std::max(0.0, t_s - a.start_s) / 3600.0;
  const double polarisation = scale(-a.polarisation_loss_per_h, hours);
  s.d *= polarisation;
  s.hysteresis *= polarisation;
  s.eps *= scale(-a.capacitance_loss_per_h, hours);
  return s;
}

// The leakage conductivity at the plant's time t [S/m]; 0 without leakage.
double leakage_conductivity(const AgingConfig& a, double t_s) noexcept {
  if (!a.enabled || !(a.leakage_resistivity_ohm_m > 0.0)) return 0.0;
  return (1.0 + a.leakage_growth_per_h * std::max(0.0, t_s - a.start_s) / 3600.0) /
         a.leakage_resistivity_ohm_m;
}

Scales with_stress(Scales s, const StressConfig& st, double stress_pa) noexcept {
  if (!st.enabled) return s;
  s.eps *= scale(st.permittivity_coefficient_per_pa, stress_pa);
  s.d *= scale(st.d_coefficient_per_pa, stress_pa);
  s.hysteresis *= scale(st.hysteresis_coefficient_per_pa, stress_pa);
  return s;
}

struct MechanicalInput {
  Scales temperature{};
  double e_v_per_m{0.0};
  double dp{0.0};
  double force_n{0.0};
};

struct MechanicalResponse {
  Scales scales{};
  double s_inst{0.0};
  double x_eq_m{0.0};
  double stress_pa{0.0};
};

// Steps 4-5 of Plant::step (plant.hpp) for a trial stress t_c, the argument of the
// stress-dependent coefficients; the creep bank and the mechanics are only peeked at.
MechanicalResponse respond(const PlantConfig& c, double length_m, const Plant::State& state,
                           const MechanicalInput& in, double t_c) noexcept {
  MechanicalResponse r{};
  r.scales = with_stress(in.temperature, c.stress, t_c);
  r.s_inst = c.material.d33_m_per_v * r.scales.d * in.e_v_per_m +
             c.hysteresis.s_amplitude * r.scales.hysteresis * in.dp;
  if (c.electrostriction.enabled) {
    const double p = c.material.permittivity_f_per_m * r.scales.eps * in.e_v_per_m +
                     c.hysteresis.d_amplitude_c_per_m2 * r.scales.hysteresis * in.dp;
    r.s_inst += c.electrostriction.q_m4_per_c2 * p * p;
  }
  const double s_free = r.s_inst + state.creep_s.peek(r.s_inst);
  const double compliance = c.material.compliance_m2_per_n * r.scales.compliance;
  const double k_s = c.geometry.cross_section_m2 / (compliance * length_m);
  r.x_eq_m = (k_s * length_m * s_free + in.force_n) / (k_s + c.mechanics.load_stiffness_n_per_m);
  const double x = c.mechanics.enabled ? state.mechanics.peek(r.x_eq_m) : r.x_eq_m;
  r.stress_pa = (x / length_m - s_free) / compliance;
  return r;
}

// The self-consistent stress T = f(T) (only with the stress effect on; otherwise f is constant). f
// is affine in T while no scale is clamped, so the secant through two trial points T_a (the last
// stress) and T_b = T_a + kStressProbePa is exact:
//   b = (f(T_b) - f(T_a)) / (T_b - T_a),   T = T_a + (f(T_a) - T_a) / (1 - b).
// b is the loop gain of the stress feedback; where 1 - b < kMinContraction no unique solution
// exists and f(T_a) (the stress with last sample's coefficients) is kept.
constexpr double kStressProbePa{1.0e6};
constexpr double kMinContraction{0.05};

double solve_stress(const PlantConfig& c, double length_m, const Plant::State& state,
                    const MechanicalInput& in) noexcept {
  const double t_a = state.t_prev_pa;
  const double f_a = respond(c, length_m, state, in, t_a).stress_pa;
  const double f_b = respond(c, length_m, state, in, t_a + kStressProbePa).stress_pa;
  const double b = (f_b - f_a) / kStressProbePa;
  if (!(1.0 - b >= kMinContraction)) return f_a;
  return t_a + (f_a - t_a) / (1.0 - b);
}

PlantConfig validated(const PlantConfig& config) {
  std::string why;
  if (!config.is_valid(&why)) throw std::invalid_argument{why};
  return config;
}

}  // namespace

Plant::Plant(const PlantConfig& config)
    : config_{validated(config)},
      derived_{derive(config_)},
      ts_{1.0 / config_.sample_rate_hz},
      heating_gain_{-std::expm1(-ts_ / config_.heating.time_constant_s)} {
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
  s.d0 = c.material.d33_m_per_v * with_stress(Scales{}, c.stress, s.t_prev_pa).d * s.t_prev_pa;
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

  const double h = c.geometry.layer_thickness_m;
  const double u =
      s.amplifier.update(input.e_cmd_v_per_m * h, s.capacitance_est_f, fx.amplifier_fault, &flags);
  const double e = u / h;

  double dp = 0.0;
  if (everett_) dp = s.preisach.update(*everett_, e) - s.p0;

  // Strain and stress at the self-consistent stress, then commit creep and mechanics.
  const double length = derived_.length_m;
  const double t_s = static_cast<double>(s.sample) * ts_;
  const MechanicalInput in{
      with_aging(temperature_scales(c.temperature, input.temp_degc + s.heating_rise_k), c.aging,
                 t_s),
      e, dp, c.mechanics.load_force_n + input.force_n};
  const double t_c = c.stress.enabled ? solve_stress(c, length, s, in) : 0.0;
  const MechanicalResponse r = respond(c, length, s, in, t_c);
  const double s_free = r.s_inst + s.creep_s.update(r.s_inst);
  const double x = c.mechanics.enabled ? s.mechanics.update(r.x_eq_m) : r.x_eq_m;
  const double strain = x / length;
  const double compliance = c.material.compliance_m2_per_n * r.scales.compliance;
  const double stress = (strain - s_free) / compliance;

  double eps_eff = c.material.permittivity_f_per_m * r.scales.eps;
  if (c.permittivity.enabled) {
    const double xe = e / c.permittivity.reference_field_v_per_m;
    eps_eff *= 1.0 + c.permittivity.linear_coefficient * xe +
               c.permittivity.quadratic_coefficient * xe * xe;
  }
  const double d_inst = eps_eff * e + c.hysteresis.d_amplitude_c_per_m2 * r.scales.hysteresis * dp;
  const double d_free = d_inst + s.creep_d.update(d_inst);
  const double d = d_free + c.material.d33_m_per_v * r.scales.d * stress;

  const double electrode_area = c.geometry.layers * c.geometry.electrode_area_m2;
  const double q = electrode_area * (d - s.d0);
  s.q_leak_c += electrode_area * leakage_conductivity(c.aging, t_s) * e * ts_;
  const double q_amp = s.charge_amplifier.update(q + s.q_leak_c, s.random);

  const double du = u - s.u_prev_v;
  if (std::abs(du) > 1e-3) {
    const double c_lin = capacitance_linear(e);
    s.capacitance_est_f = std::clamp((q - s.q_prev_c) / du, c_lin, 10.0 * c_lin);
  }
  const double stack_temp_degc = input.temp_degc + s.heating_rise_k;
  if (c.heating.enabled) {
    const double volume = electrode_area * c.geometry.layer_thickness_m;
    const double power =
        volume * 0.5 * (e + s.last.e_v_per_m) * ((d - s.d0) - s.last.d_c_per_m2) / ts_;
    s.heating_rise_k +=
        heating_gain_ * (c.heating.thermal_resistance_k_per_w * power - s.heating_rise_k);
  }
  s.u_prev_v = u;
  s.q_prev_c = q;
  s.t_prev_pa = stress;

  // Every channel is sampled every time, so faults never shift the random sequence.
  const Measurement fresh{
      s.channel_e.measure(fx.disconnect_e ? 0.0 : e, s.random, &flags),
      s.channel_d.measure(fx.disconnect_d ? 0.0 : q_amp / electrode_area, s.random, &flags)};
  const Measurement measured = apply_faults(
      fx, fresh, Measurement{s.last.e_meas_v_per_m, s.last.d_meas_c_per_m2},
      Measurement{s.channel_e.out_of_range_value(), s.channel_d.out_of_range_value()}, &flags);

  StepOutput out{};
  out.t_s = t_s;
  out.e_meas_v_per_m = measured.e_v_per_m;
  out.d_meas_c_per_m2 = measured.d_c_per_m2;
  out.e_v_per_m = e;
  out.d_c_per_m2 = d - s.d0;
  out.s = strain;
  out.t_pa = stress;
  out.u_v = u;
  out.q_c = q;
  out.x_m = x;
  out.f_n = stress * c.geometry.cross_section_m2;
  out.temp_degc = stack_temp_degc;
  out.polarisation = dp + s.p0;
  out.q_amp_c = q_amp;
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
