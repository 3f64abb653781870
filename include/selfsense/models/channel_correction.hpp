// Physics a diagnosis adds to one output channel of a transducer model (selfsense diagnose,
// docs/diagnose.md): terms after the model's own output y of that channel, then linear filters.
//
//   v = y + gain y + offset                                      offset (gain and offset error)
//         + temperature_gain (theta - theta_ref) y
//         + temperature_offset (theta - theta_ref)               temperature_dependence
//         + temperature_drive (theta - theta_ref) x
//         + temperature_stress (theta - theta_ref) T             (a coupling that moves apart
//                                                                from the loop and permittivity)
//         + temperature_gain2 (theta - theta_ref)^2 y
//         + temperature_offset2 (theta - theta_ref)^2            (quadratic in the change)
//         + temperature_drive2 (theta - theta_ref)^2 x
//         + temperature_stress2 (theta - theta_ref)^2 T
//         + stress_gain T r + stress_quadratic T^2               stress_dependence
//         + stress_drive T x + stress_linear T                   (the permittivity, the
//                                                                coupling moving with stress)
//         + drive_quadratic x^2 + drive_cubic x^3                permittivity_nonlinearity
//         + sensed_quadratic s^2                                 electrostriction (S ~ P^2,
//                                                                P ~ D - d T)
//         + sum_j creep_weights_j (z_j - r_0)                    creep (eq. 28: K = L[H])
//         + sum_j drive_creep_weights_j (u_j - x_0)              creep driven by the input
//         + drive_integral q                                     charge_leakage: the current
//                                                                through the stack's parallel
//                                                                conductance
//         + drive_linear x + sum_i hysteresis_weights_i (p_i - x)
//                                                                hysteresis (a PI operator of
//                                                                the drive: its linear play and
//                                                                the plays p_i)
//         + sum_h hinge_weights_h max(0, p_{r_h} - b_h)          asymmetric_hysteresis (hinges
//                                                                on the plays: the Preisach class)
//   p_i[k] = max(x[k] - r_i, min(x[k] + r_i, p_i[k-1])),  p_i = x at the start (p_0 = x)
//   z_j[k] = z_j[k-1] + (1 - exp(-lambda_j Ts)) (r[k] - z_j[k-1]),  z_j = r_0 = r at the start
//   u_j[k] = u_j[k-1] + (1 - exp(-mu_j Ts)) (x[k] - u_j[k-1]),   u_j = x_0 = x at the start
//   q[k] = q[k-1] + Ts x[k],  q = 0 at the start  (the field's integral [drive unit s])
//   w = second-order low-pass of v, unity DC gain, f0 and zeta    dynamics
//       (bilinear transform prewarped at f0); with a second mode or a direct path
//   w = (1 - a - b) H1[v] + a v + b H2[v]                       (two modes in parallel, H2 at
//       f2 and zeta2, and a share a of v that passes neither: unity DC gain still)
//   m[k] = g m[k-1] + c (w[k] - w[k-1]),  g = exp(-Ts/tau), c = (1 - g) tau / Ts,  m = w at the
//       start                                                     charge_leakage
//   out[k] = m(k Ts - delay)  (delay <= 64 samples; below one sample linear      delay
//       interpolation, from one on the cubic through four samples: models/cubic_read.hpp)
// x: the drive (E for field drive), T: stress [Pa], theta: temperature [degC], s: the model's
// sensed response to the drive alone (D - d T, d the sensor's coupling), r = y - coupling T the
// channel's response to the drive alone (so a coupling that changes with stress,
// d(T) = d (1 + k T), is k T r on S and d k T^2 on D). Units: gain, temperature_gain [1/K],
// stress_gain [1/Pa] relative, stress_drive [channel unit / (drive unit Pa)], stress_linear
// [channel unit / Pa], temperature_gain2 [1/K^2]; offset, drive_linear and the polynomial terms
// in the channel's unit (per unit of the drive to its power); temperature_stress [channel unit /
// (Pa K)], temperature_stress2 [channel unit / (Pa K^2)]; drive_integral in the channel's unit per
// (drive unit s): for D under field drive the conductivity [S/m].
//
// Reconstruction needs the inverse on the sensed channel: the leakage is undone
// (w[k] = w[k-1] + (m[k] - g m[k-1]) / c), a delay moves to the drive, and the additive and
// gain terms that do not depend on T (the play terms, the drive's lags and its integral depend
// on the drive alone; the integral of the delayed drive starts at -delay x0, so that it is the
// forward integral a delay later; the creep lags
// follow the response r = y - d T, which for the affine models is G_s[x] + y0_s, known from the
// drive before y: the caller passes it) are solved for y; the terms in T are solved with the
// sensor coupling d after the kernel: (d + k') T + q' T^2 = d T_lin, with q' = q / g,
//   k' = (stress_gain r + stress_drive x + stress_linear
//         + (temperature_stress + temperature_stress2 dtheta) dtheta) / g,
// dtheta = theta - theta_ref, g = 1 + gain terms, r again the response to the drive alone. Terms
// that depend on y's own history (dynamics) make the sensor side non-invertible in closed form:
// invertible() says so and the Reconstruction refuses such a model by name.
//
// Real-time safe after construction: step(), filter(), invert(), save/restore are noexcept and
// allocate nothing.
#pragma once

#include <array>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace selfsense::models {

struct ChannelCorrection {
  double gain{0.0};
  double offset{0.0};
  double temperature_reference_degc{25.0};
  double temperature_gain_per_k{0.0};
  double temperature_offset_per_k{0.0};
  double temperature_drive_per_k{0.0};
  double temperature_gain_per_k2{0.0};    // [1/K^2]
  double temperature_offset_per_k2{0.0};  // [channel unit / K^2]
  double temperature_drive_per_k2{0.0};   // [channel unit / (drive unit K^2)]
  double temperature_stress_per_k{0.0};   // [channel unit / (Pa K)]
  double temperature_stress_per_k2{0.0};  // [channel unit / (Pa K^2)]
  // Times the field's integral [channel unit / (drive unit s)]: the current through a parallel
  // conductance of the stack, which the charge amplifier collects (sigma [S/m] for D).
  double drive_integral_per_s{0.0};
  double stress_gain_per_pa{0.0};
  double stress_quadratic_per_pa2{0.0};
  double stress_drive_per_pa{0.0};   // [channel unit / (drive unit Pa)]
  double stress_linear_per_pa{0.0};  // [channel unit / Pa]
  double drive_quadratic{0.0};
  double drive_cubic{0.0};
  double drive_linear{0.0};  // the PI operator's linear play (hysteresis)
  double sensed_quadratic{0.0};
  std::vector<double> creep_eigenvalues{};  // [1/s]
  std::vector<double> creep_weights{};
  std::vector<double> drive_creep_eigenvalues{};  // [1/s] (mu_j)
  std::vector<double> drive_creep_weights{};      // [channel unit / drive unit]
  double dynamics_frequency_hz{0.0};              // 0: none
  double dynamics_damping{0.0};
  double dynamics_direct{0.0};         // a: the share of v that passes no mode
  double dynamics2_frequency_hz{0.0};  // 0: one mode
  double dynamics2_damping{0.0};
  double dynamics2_share{0.0};                  // b: the second mode's share
  double leakage_tau_s{0.0};                    // 0: none
  double delay_s{0.0};                          // 0: none
  std::vector<double> hysteresis_thresholds{};  // r_i > 0, increasing [unit of the drive]
  std::vector<double> hysteresis_weights{};
  std::vector<double> hinge_thresholds{};  // each 0 or one of hysteresis_thresholds
  std::vector<double> hinge_levels{};      // b_h [unit of the drive]
  std::vector<double> hinge_weights{};

  // Every value finite, sizes agree, dynamics_damping > 0 with a frequency (each mode), a
  // second mode, a direct share or a second share only beside a first mode, taus and delay
  // >= 0; names the key under `prefix` ("corrections.sensed.leakage_tau_s: ...").
  [[nodiscard]] bool is_valid(const std::string& prefix, std::string* why) const;
  // Closed-form inverse exists (header comment); otherwise *why names the term.
  [[nodiscard]] bool invertible(const std::string& prefix, std::string* why) const;
  [[nodiscard]] bool empty() const noexcept;
  [[nodiscard]] bool plays_valid(const std::string& prefix, std::string* why) const;
  friend bool operator==(const ChannelCorrection&, const ChannelCorrection&) = default;
};

inline constexpr std::size_t kMaxCorrectionDelaySamples{64};
inline constexpr std::size_t kMaxCorrectionCreep{12};
inline constexpr std::size_t kMaxCorrectionPlays{16};
inline constexpr std::size_t kMaxCorrectionHinges{64};

// The dynamics term's second-order low-pass (unity DC gain, natural frequency f0, damping zeta)
// by the bilinear transform prewarped at f0:
//   w[k] = b0 (v[k] + 2 v[k-1] + v[k-2]) - a1 w[k-1] - a2 w[k-2]
// with k = w0 / tan(w0 Ts / 2), a0 = k^2 + 2 zeta w0 k + w0^2, b0 = w0^2 / a0,
// a1 = 2 (w0^2 - k^2) / a0, a2 = (k^2 - 2 zeta w0 k + w0^2) / a0.
// Throws std::invalid_argument at or above 0.95 Nyquist.
struct ModeCoefficients {
  double b0{1.0};
  double a1{0.0};
  double a2{0.0};
};
[[nodiscard]] ModeCoefficients mode_coefficients(double frequency_hz, double damping,
                                                 double sample_time);

class CorrectionStage {
 public:
  struct Inputs {
    double y{0.0};            // the model's output of this channel (forward) ...
    double drive{0.0};        // x
    double stress{0.0};       // T [Pa]
    double temperature{0.0};  // [degC]
    double sensed{0.0};       // the model's sensed response D - d T (electrostriction term)
    double response{0.0};     // y - coupling T (stress term)
  };

  // Throws std::invalid_argument if the correction is invalid, the delay exceeds
  // kMaxCorrectionDelaySamples at this sample time, or there are too many creep terms.
  CorrectionStage(const ChannelCorrection& correction, double sample_time);

  // Forward: the corrected output for this sample.
  double step(const Inputs& in) noexcept;
  // The filters alone (dynamics, leakage, delay) on v, as step() runs them after the terms:
  // for a correction that has no terms (identification filters each regressor column so).
  double filter(double v) noexcept;
  // Sensed-channel inverse (only for invertible() corrections): the model output y that
  // explains the measurement `measured` at this sample; `in.y` is ignored, the drive must
  // already be delayed by the caller (delay_samples()) and, with creep terms, `in.response` is
  // the sensor's response to that drive alone.
  double invert(double measured, const Inputs& in) noexcept;
  // After the kernel: the stress that solves the terms in T (stress_gain, stress_quadratic,
  // stress_drive, temperature-stress), from the kernel's T_lin and the sensor coupling d (T_lin
  // itself without them); with stress_gain, `in.response` is the response to the drive alone.
  [[nodiscard]] double solve_stress(double t_lin, double coupling, const Inputs& in) const noexcept;
  // The drive delayed by this channel's delay (reconstruction feeds it to the kernel).
  double delay_drive(double drive) noexcept;

  [[nodiscard]] const ChannelCorrection& correction() const noexcept { return c_; }
  // The inverse reads Inputs::response (creep terms, stress_gain).
  [[nodiscard]] bool reads_response() const noexcept {
    return creep_count_ > 0 || c_.stress_gain_per_pa != 0.0;
  }
  [[nodiscard]] static constexpr std::size_t state_size() noexcept { return kStateSize; }
  void save_state(std::span<double> out) const noexcept;
  void restore_state(std::span<const double> in) noexcept;

 private:
  static constexpr std::size_t kLine = kMaxCorrectionDelaySamples + 2;
  static constexpr std::size_t kStateSize =
      17 + 2 * kMaxCorrectionCreep + kMaxCorrectionPlays + 2 * kLine;

  double terms(const Inputs& in) const noexcept;  // the additive/gain terms except creep and T
  // stress_gain r + stress_drive x + stress_linear + (temperature_stress + temperature_stress2
  // dtheta) dtheta: the change of the stress coupling.
  double stress_coupling_change(const Inputs& in) const noexcept;
  double gain_at(const Inputs& in) const noexcept;
  double filters(double v) noexcept;         // dynamics, leakage, delay
  double play_terms(double drive) noexcept;  // advances the plays; hysteresis + hinge terms
  // Advances the drive's lags and integral; their terms. `integral_start`: the integral's value
  // at the first sample (0 forward; -delay x0 for the delayed drive of the inverse).
  double drive_memory_terms(double drive, double integral_start) noexcept;
  double delayed(double value) noexcept;
  double push_delayed(std::array<double, kLine>& line, std::size_t& head,
                      double value) const noexcept;

  ChannelCorrection c_;
  std::array<double, kMaxCorrectionCreep> alpha_{};  // 1 - exp(-lambda Ts)
  std::size_t creep_count_{0};
  std::array<double, kMaxCorrectionCreep> drive_alpha_{};  // 1 - exp(-mu Ts)
  std::size_t drive_creep_count_{0};
  double ts_{0.0};
  // Dynamics: w[k] = b0 v[k] + b1 v[k-1] + b2 v[k-2] - a1 w[k-1] - a2 w[k-2]; the second
  // mode the same with its own coefficients and outputs (its inputs are v's).
  double b0_{1.0}, b1_{0.0}, b2_{0.0}, a1_{0.0}, a2_{0.0};
  ModeCoefficients second_{};
  double direct_{0.0}, second_share_{0.0};
  double leak_g_{0.0}, leak_c_{1.0};
  std::size_t delay_whole_{0};
  double delay_frac_{0.0};
  std::array<double, kMaxCorrectionPlays + 1> play_r_{};  // r_0 = 0, then the thresholds
  std::size_t play_count_{0};                             // plays besides p_0 = x
  std::array<std::size_t, kMaxCorrectionHinges> hinge_row_{};
  std::size_t hinge_count_{0};
  // State (saved in this order): started, y0, v1, v2, w1, w2, m, w_prev, head, drive_head,
  // drive_started, plays_started, memory_started, x0, integral, second_w1, second_w2; creep z;
  // drive lags u; plays; the output and drive delay lines (rings).
  bool memory_started_{false};
  double x0_{0.0};
  double integral_{0.0};
  std::array<double, kMaxCorrectionCreep> u_{};
  double y0_{0.0};
  double v1_{0.0}, v2_{0.0}, w1_{0.0}, w2_{0.0};
  double second_w1_{0.0}, second_w2_{0.0};
  double m_{0.0}, w_prev_{0.0};
  std::array<double, kMaxCorrectionCreep> z_{};
  std::array<double, kMaxCorrectionPlays> plays_{};
  std::array<double, kLine> line_{};
  std::size_t head_{0};
  std::array<double, kLine> drive_line_{};
  std::size_t drive_head_{0};
  bool dynamics_{false};
  bool mixed_modes_{false};  // a direct path or a second mode beside the first
  bool leakage_{false};
  bool delay_{false};
  bool started_{false};
  bool drive_started_{false};
  bool plays_started_{false};
};

}  // namespace selfsense::models
