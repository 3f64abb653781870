// Configuration of the simulated piezo stack (the "plant"): plain structs with realistic
// defaults for a multilayer stack of about 10 mm, 15 um stroke at 2e6 V/m, 1.4 uF and
// about 1 kN blocking force. Every effect has an `enabled` switch; the clean stack is
// linear piezoelectricity with ideal amplifier and sensors.
//
// Units are SI and part of every key name. The YAML loader (plant_yaml.hpp) maps these structs
// one to one onto the `plant:` section, so a key path like plant.mechanics.resonance_hz names
// the member mechanics.resonance_hz here.
//
// Terminal quantities relate to the field quantities through the geometry:
//   u = E * h, q = D * A_el * n, x = S * L (L = n * h), F = T * A_mech.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace selfsense::plant {

struct GeometryConfig {
  int layers{167};
  double layer_thickness_m{60e-6};
  double electrode_area_m2{25e-6};  // per layer
  double cross_section_m2{25e-6};   // mechanical cross-section A_mech
};

// Linear small-signal coefficients at the reference temperature and zero stress.
struct MaterialConfig {
  double permittivity_f_per_m{2.0e-8};  // eps^T, relative permittivity about 2260
  double d33_m_per_v{5.5e-10};          // d, also C/N
  double compliance_m2_per_n{3.5e-11};  // s^E of the stack including glue layers
};

// Discretised Preisach model: relays r(alpha, beta) with switching fields beta <= alpha on
// [field_min, field_max], density (normalised to total weight 1)
//   mu(alpha, beta) = exp(-(w - width_center)^2 / (2 width_sigma^2))
//                   * exp(-(b - bias_center)^2 / (2 sigma_b^2)),
//   w = (alpha - beta) / 2, b = (alpha + beta) / 2,
//   sigma_b = bias_sigma * (1 + asymmetry) for b > bias_center, * (1 - asymmetry) below.
// The output p in [-1, 1] (all relays down .. up) drives both channels:
//   D += d_amplitude * (p - p0), S += s_amplitude * (p - p0)   (p0: state at reset).
struct HysteresisConfig {
  bool enabled{false};
  double field_min_v_per_m{-1.0e6};
  double field_max_v_per_m{3.0e6};
  int levels{96};  // Everett table resolution
  double width_center_v_per_m{3.0e5};
  double width_sigma_v_per_m{3.0e5};
  double bias_center_v_per_m{1.0e6};
  double bias_sigma_v_per_m{6.0e5};
  double asymmetry{0.3};  // in (-1, 1)
  double d_amplitude_c_per_m2{0.012};
  double s_amplitude{2.5e-4};
};

// Bank of first-order relaxation elements, each following the instantaneous (creep-free)
// response y of its channel:  z_j[k] = z_j[k-1] + (1 - exp(-Ts / tau_j)) * (y[k] - z_j[k-1]),
// creep contribution = sum_j weight_j * (z_j - y0) (y0: response at reset), so the output after a
// step keeps moving by weight_j of the step with time constant tau_j and then settles.
struct CreepConfig {
  bool enabled{false};
  std::vector<double> tau_s{0.004, 0.03, 0.35, 2.8, 25.0, 150.0};
  std::vector<double> s_weights{0.012, 0.012, 0.015, 0.015, 0.018, 0.02};
  std::vector<double> d_weights{0.008, 0.008, 0.01, 0.01, 0.012, 0.012};
};

// eps(E) = eps * (1 + linear * E / E_ref + quadratic * (E / E_ref)^2).
struct PermittivityConfig {
  bool enabled{false};
  double linear_coefficient{0.25};
  double quadratic_coefficient{0.1};
  double reference_field_v_per_m{2.0e6};
};

// Electrostriction: the strain follows the square of the polarization,
//   S += q * P^2,   P = eps E + d_amplitude (p - p0)   [C/m^2] (the stress-free polarization),
// so bipolar drive past the coercive field draws butterfly loops; q in m^4/C^2 (PZT: ~0.02).
struct ElectrostrictionConfig {
  bool enabled{false};
  double q_m4_per_c2{0.02};
};

// d(T) = d * (1 + d_coefficient * T), hysteresis amplitudes * (1 + hysteresis_coefficient * T),
// eps(T) = eps * (1 + permittivity_coefficient * T); T in Pa (compression < 0), the stack stress
// of the same sample (Plant::step solves for it). Large compression therefore shrinks the
// coupling and the loops. Every scale is kept >= 0.05 (also for temperature).
struct StressConfig {
  bool enabled{false};
  double d_coefficient_per_pa{8e-9};
  double hysteresis_coefficient_per_pa{1.5e-8};
  double permittivity_coefficient_per_pa{4e-9};
};

// Coefficient c(temp) = c * (1 + k * (temp - reference)); temp comes from the step input.
struct TemperatureConfig {
  bool enabled{false};
  double reference_degc{25.0};
  double permittivity_coefficient_per_k{4e-3};
  double d_coefficient_per_k{2e-3};
  double hysteresis_coefficient_per_k{-4e-3};
  double compliance_coefficient_per_k{5e-4};
};

// Aging (issue 24 item 4, docs/health.md), linear in the plant's age from start_s,
// t_h = max(0, t - start_s) / 3600 s [h]:
//   a_p(t) = max(0.05, 1 - polarisation_loss_per_h t_h)   scales d and the loop amplitudes of
//                                                          D and S (the remanent polarisation)
//   a_c(t) = max(0.05, 1 - capacitance_loss_per_h t_h)    scales the permittivity
//   sigma(t) = (1 + leakage_growth_per_h t_h) / leakage_resistivity_ohm_m     [S/m]
// the last an insulation leakage in parallel with the stack: the amplifier delivers, and the
// charge amplifier counts, q_leak[k] = q_leak[k-1] + n A_el sigma(t) E Ts on top of the
// stack's charge. leakage_resistivity_ohm_m 0: no leakage. Off by default.
struct AgingConfig {
  bool enabled{false};
  double polarisation_loss_per_h{0.0};    // [1/h] (0.05: 5 % per hour)
  double capacitance_loss_per_h{0.0};     // [1/h]
  double leakage_resistivity_ohm_m{0.0};  // at t = 0 [Ohm m]; 0: none
  double leakage_growth_per_h{0.0};       // relative growth of the conductivity [1/h]
  double start_s{0.0};                    // the stack ages from this plant time on [s]
};

// Self-heating (issue 24 item 4, docs/health.md): the stack's temperature rises over the input
// temperature with the electrical power it takes, through a thermal resistance R_th and a time
// constant tau (first order, exact for a power held over a sample):
//   P[k]    = V (E[k] + E[k-1]) / 2 (D[k] - D[k-1]) / Ts        V = n A_el h       [W]
//   rise[k] = rise[k-1] + (1 - exp(-Ts / tau)) (R_th P[k] - rise[k-1])               [K]
// and the coefficients of sample k see input.temp_degc + rise[k-1]. Over a drive cycle the
// reactive part of P cancels and its mean is the loop area times V times the drive frequency,
// so the steady state is rise = R_th W V f; tau much longer than the period smooths the rest.
// Off by default.
struct HeatingConfig {
  bool enabled{false};
  double thermal_resistance_k_per_w{50.0};  // R_th, stack to ambient [K/W]
  double time_constant_s{120.0};            // tau = R_th C_th [s]
};

// Stack and load as one mass-spring-damper:
//   m x'' + c x' + (k_s + k_load) x = k_s L S_free + F_ext,   k_s = A_mech / (s^E L),
// m = (k_s + k_load) / (2 pi resonance_hz)^2, c = 2 zeta sqrt((k_s + k_load) m).
// Discretised exactly with x_eq ramping linearly between samples (first-order hold,
// mechanics.hpp). Off: quasi-static (m = 0).
// Stress in the stack T = (x / L - S_free) / s^E.
struct MechanicsConfig {
  bool enabled{false};
  double resonance_hz{8000.0};
  double damping_ratio{0.03};
  double load_stiffness_n_per_m{0.0};
  double load_force_n{0.0};  // static applied force (+ pulls, - compresses); input adds to it
};

// Charge amplifier with feedback resistance: the measured charge forgets with tau,
//   q_m[k] = exp(-Ts/tau) q_m[k-1] + (q[k] - q[k-1]) * (1 - exp(-Ts/tau)) / (Ts/tau),
// plus an offset q_off(t) = offset + drift * t + random walk (sigma * sqrt(Ts) per sample);
// the offset terms act only with drift_enabled.
struct ChargeAmplifierConfig {
  bool leakage_enabled{false};
  double leakage_tau_s{20.0};
  bool drift_enabled{false};
  double offset_c{0.0};
  double drift_c_per_s{2e-9};
  double random_walk_c_per_sqrt_s{1e-9};
};

// Voltage amplifier driving the stack: u follows the command within [voltage_min, voltage_max],
// |du/dt| <= slew_rate and |i| = C_est |du/dt| <= current_limit, C_est the stack's incremental
// capacitance (linear estimate, raised by the last measured dq/du).
struct AmplifierConfig {
  bool enabled{false};
  double voltage_min_v{-20.0};
  double voltage_max_v{120.0};
  double slew_rate_v_per_s{2.0e5};
  double current_limit_a{0.5};
};

// One sensor channel as the controller sees it: delay, additive Gaussian noise, ADC.
struct AdcConfig {
  bool enabled{false};
  int bits{16};
  double min{0.0};
  double max{1.0};
};

struct ChannelConfig {
  int delay_samples{0};  // 0 .. kMaxDelaySamples
  double noise_std{0.0};
  AdcConfig adc{};
};

struct SensorsConfig {
  ChannelConfig e{0, 0.0, AdcConfig{false, 18, -1.0e6, 3.0e6}};  // V/m
  ChannelConfig d{0, 0.0, AdcConfig{false, 18, -0.05, 0.15}};    // C/m^2
};

enum class FaultKind : std::uint8_t {
  stuck_adc,
  nan_sample,
  out_of_range,
  missed_data_ready,
  late_sample,
  amplifier_fault,
  sensor_disconnect,
};

enum class Channel : std::uint8_t { e, d, both };

// A scheduled fault: active for samples [start, start + duration) of simulated time.
struct FaultEntry {
  FaultKind kind{FaultKind::nan_sample};
  Channel channel{Channel::d};
  double start_s{0.0};
  double duration_s{0.0};  // 0: one sample
  double late_by_s{0.0};   // late_sample only: how late the sample arrives
};

struct PlantConfig {
  double sample_rate_hz{100000.0};
  std::uint64_t seed{1};
  GeometryConfig geometry{};
  MaterialConfig material{};
  HysteresisConfig hysteresis{};
  CreepConfig creep{};
  PermittivityConfig permittivity{};
  ElectrostrictionConfig electrostriction{};
  StressConfig stress{};
  TemperatureConfig temperature{};
  AgingConfig aging{};
  HeatingConfig heating{};
  MechanicsConfig mechanics{};
  ChargeAmplifierConfig charge_amplifier{};
  AmplifierConfig amplifier{};
  SensorsConfig sensors{};
  std::vector<FaultEntry> faults{};

  // Checks every constraint; on failure writes "plant.<key path>: <value>: <violated
  // constraint>" to *why (if non-null) and returns false.
  [[nodiscard]] bool is_valid(std::string* why) const;
};

inline constexpr int kMaxDelaySamples{64};
inline constexpr std::size_t kMaxCreepElements{16};
inline constexpr std::size_t kMaxScheduledFaults{64};

[[nodiscard]] const char* to_string(FaultKind kind) noexcept;
[[nodiscard]] const char* to_string(Channel channel) noexcept;

// Derived quantities of the geometry and material at the reference temperature.
struct Derived {
  double length_m{};
  double capacitance_f{};            // n eps A_el / h (linear, small signal)
  double stack_stiffness_n_per_m{};  // A_mech / (s^E L)
  double free_stroke_m{};            // d * E_full * L at E_full = 2e6 V/m (linear part)
  double blocking_force_n{};         // k_s * free_stroke
  double effective_mass_kg{};        // 0 when mechanics is off
};
[[nodiscard]] Derived derive(const PlantConfig& config) noexcept;

}  // namespace selfsense::plant
