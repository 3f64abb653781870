// An independent piezo stack simulation for the diagnosis proof (issue 23, item 4): a second
// generator written apart from the plant (src/plant) and from the operators the candidates are
// built of (src/operators): standard library only, its own hysteresis (a Preisach model with a
// density of its own, below), its own form of every effect, its own excitation. Everything is
// drawn from one seed (std::mt19937_64 and this file's own uniform and normal transforms, so a
// seed gives the same recording with any standard library).
//
// The stack, per sample k (Ts = 1 / fs), field E [V/m], stress T [Pa] (compression < 0),
// temperature theta [degC]:
//   u = E / E_ref                                 normalised field, E_ref = 2e6 V/m
//   F = -Ev(H, L) + 2 sum_k [Ev(M_k, m_(k-1)) - Ev(M_k, m_k)]
//                                                 Preisach output in [-1, 1]: Ev the Everett
//                                                 function of the density below on [L, H],
//                                                 M_k, m_k the dominant extrema of E so far
//                                                 (wiping out), the last one E itself
//   Fn = (F - F_0) / (F_1 - F_0)                  normalised: 0 at E = 0, 1 at E = E_ref on the
//                                                 major loop 0 .. E_ref
//   y = u + c_loop chi (Fn - u)                   hysteretic, ~0 .. 1; chi the hysteretic share
//   P = p y                                       polarization [C/m^2]
//   D = c_eps eps E + P + c_d d T                 [C/m^2]
//   S = c_d g P + s T                             [-] (no P^2: electrostriction is an effect the
//                                                 diagnosis names; a clean stack has none)
// Density of relays (alpha >= beta) with half-width w = (alpha - beta) / 2 and centre
// c = (alpha + beta) / 2 (log-normal widths, skewed Cauchy centres; the plant's is Gaussian in
// both):
//   mu = exp(-ln(w / w_m)^2 / (2 sw^2)) / w * 1 / (1 + ((c - c0) / gc)^2),
//   gc = g (1 + a) above c0 and g (1 - a) below.
// The scales c are 1 on the clean stack; the stress effect makes them 1 + k T, the temperature
// effect 1 + a (theta - 25) + b (theta - 25)^2. Then, in this order: creep lags added to S
// and/or D, charge leakage on D, mechanical modes on S, a sampling delay of D or S, sensor
// noise (Gaussian, a drawn share of each channel's nominal range).
//
// Effect forms (each drawn per case; m the magnitude, calibrated by the harness):
//   creep       lags over decades (Tustin): z_j[k] = a_j z_j[k-1] + b_j (x[k] + x[k-1]),
//               a_j = (2 tau_j - Ts) / (2 tau_j + Ts), b_j = Ts / (2 tau_j + Ts), driven by
//               x = u (the input) or x = y (the hysteresis output); S += m k_S sum w_j (z_j - x0)
//               and/or D += m k_D sum v_j (z_j - x0), k_S, k_D the channel's response per unit x
//   leakage     high-pass of the charge: Dm[k] = g (Dm[k-1] + D[k] - D[k-1]), g =
//               exp(-Ts m / tau); or charge through the stack's parallel conductance sigma:
//               Dm = D + m sigma sum Ts (E[k] + E[k-1]) / 2  (sigma = eps_eff / tau)
//   stress      c_d = 1 + m k_d T, c_eps = 1 + m k_eps T, c_loop = 1 + m k_loop T
//   temperature c_x = 1 + m (a_x dtheta + b_x dtheta^2) for permittivity, coupling, loop; the
//               temp column a ramp (linear or a self-heating approach) or a slow swing
//   dynamics    one or two modes on S: w'' + 2 zeta omega w' + omega^2 w = omega^2 S (RK4,
//               S ramping linearly between samples), S_m = sum share_i ((1 - a) S + a w_i);
//               f_i = f0_i / m (30 Hz .. 0.45 fs) with a = 1; where f would pass 0.45 fs it
//               stays there and the participation a falls with m instead
//   delay       D or S sampled m delta0 samples late (cubic interpolation of the channel)
//
// The bench: 1-2 kHz, 60-90 s per recording, E within the amplifier's range (about -0.1 ..
// 2 MV/m): steps with holds of 0.5-6 s (edges of 0.5-4 ms), sines of 0.2-5 Hz, decaying loops,
// band-limited noise, each once in a random order and then at random; an identification
// recording starts with major loops over the whole range. Load: a preload of -2 .. -4 MPa, a
// slow sine of 0.5-1.5 MPa and band-limited load noise. temp: 25 degC, or with the temperature
// effect a ramp of 10-25 K or a slow swing of that span.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <string_view>
#include <vector>

namespace selfsense::independent {

enum class Effect : std::uint8_t {
  kNone,
  kCreep,
  kLeakage,
  kStress,
  kTemperature,
  kDynamics,
  kDelay,
  kCreepLeakage
};
inline constexpr std::array<Effect, 8> kEffects{
    Effect::kNone,        Effect::kCreep,    Effect::kLeakage, Effect::kStress,
    Effect::kTemperature, Effect::kDynamics, Effect::kDelay,   Effect::kCreepLeakage};
// "none", "creep", "leakage", "stress", "temperature", "dynamics", "delay", "creep_leakage".
[[nodiscard]] const char* to_string(Effect e) noexcept;
[[nodiscard]] std::optional<Effect> parse_effect(std::string_view name) noexcept;

// The Preisach density (header comment), fields in V/m.
struct Density {
  double width_median{0.25e6};     // w_m
  double width_spread{0.6};        // sw
  double centre{1.0e6};            // c0
  double centre_halfwidth{0.8e6};  // g
  double asymmetry{0.0};           // a, in (-1, 1)
};

// The stack's material (clean, at 25 degC and zero stress).
struct Stack {
  double field_ref{2.0e6};  // E_ref [V/m]
  Density density{};
  double preisach_low{0.0};      // F_0
  double preisach_high{1.0};     // F_1
  double hysteresis_share{0.0};  // chi (tuned to the drawn loop width)
  double permittivity{0.0};      // eps [F/m], the anhysteretic part of D
  double polarization{0.0};      // p [C/m^2] per unit y
  double coupling{0.0};          // d [C/N]
  double strain_per_p{0.0};      // g [m^2/C]
  double compliance{0.0};        // s [1/Pa]
  double loop_fraction{0.0};     // drawn width of the S loop on a full sweep, share of the stroke
};

// Scales of the stack's coefficients at one sample (stress and temperature effects).
struct Scales {
  double permittivity{1.0};
  double coupling{1.0};
  double loop{1.0};
};

// The Preisach operator F[E] of a density: an Everett table on [L, H] = [-0.5, 1.5] E_ref
// (bilinear between its nodes) and the alternating dominant extrema. Starts poled: from H down
// to the first input.
class Preisach final {
 public:
  Preisach(const Density& density, double field_ref);
  double step(double e);
  [[nodiscard]] double everett(double alpha, double beta) const;

 private:
  double lo_{0.0};
  double hi_{0.0};
  double delta_{0.0};
  std::size_t n_{0};               // intervals
  std::vector<double> table_{};    // Ev at the nodes (alpha_i >= beta_j), row-major
  std::vector<double> extrema_{};  // m_0 = L, M_1, m_1, ...; the last one the input
};

// The quasi-static stack (the first block of the header comment).
class StackModel final {
 public:
  explicit StackModel(const Stack& stack);
  struct Output {
    double d{0.0};  // [C/m^2]
    double s{0.0};  // [-]
    double y{0.0};  // hysteresis output (normalised)
    double u{0.0};  // normalised field
  };
  Output step(double e, double t, const Scales& c);
  // Strain and charge per unit of y and u (the creep lags' channel gains k_S, k_D).
  [[nodiscard]] double strain_per_unit() const noexcept;
  [[nodiscard]] double charge_per_unit() const noexcept;

 private:
  Stack stack_;
  Preisach preisach_;
};

// Width of the strain loop on a triangle sweep 0 -> E_ref -> 0 (third cycle, T = 0): the largest
// difference between the falling and the rising branch at the same field, over the stroke.
[[nodiscard]] double strain_loop_fraction(const Stack& stack);

// Sensor noise, standard deviation as a share of the channel's nominal range.
struct Noise {
  double e{0.0};
  double d{0.0};
  double s{0.0};
  double t{0.0};
};

struct CreepForm {
  bool on_strain{false};
  bool on_charge{false};
  bool driven_by_output{false};  // lags of y (the hysteresis output) instead of u
  std::vector<double> tau_s{};
  std::vector<double> strain_weights{};  // w_j, share of the driver's response per lag
  std::vector<double> charge_weights{};  // v_j
};

struct LeakageForm {
  bool conductance{false};  // else the high-pass
  double tau_s{0.0};        // at magnitude 1: high-pass tau, or eps_eff / sigma
};

struct StressForm {
  double coupling_per_pa{0.0};
  double permittivity_per_pa{0.0};
  double loop_per_pa{0.0};
};

struct TemperatureForm {
  bool swing{false};                     // else a ramp
  std::array<double, 3> linear_per_k{};  // permittivity, coupling, loop
  std::array<double, 3> quadratic_per_k2{};
};

struct Mode {
  double frequency_hz{0.0};
  double damping{0.0};
  double share{1.0};
};

struct DynamicsForm {
  std::vector<Mode> modes{};
};

struct DelayForm {
  bool on_strain{false};  // else D
  double samples{0.0};    // at magnitude 1
};

// One case: the stack, the bench, the effect's form, its magnitude and the seeds of the two
// recordings (excitation 0: identification, 1: validation).
struct Draw {
  std::uint64_t seed{0};
  Effect effect{Effect::kNone};
  std::string form{};  // "leakage:conductance", "creep:S+D:output", ...
  double sample_rate_hz{1000.0};
  double field_min{0.0};  // [V/m]
  double field_max{2.0e6};
  Stack stack{};
  Noise noise{};
  CreepForm creep{};
  LeakageForm leakage{};
  StressForm stress{};
  TemperatureForm temperature{};
  DynamicsForm dynamics{};
  DelayForm delay{};
  double magnitude{1.0};   // scales the effect (creep_leakage: the creep)
  double magnitude2{1.0};  // creep_leakage: the leakage
  double ratio{1.0};       // drawn target: residual of the affected channel over the clean one
  std::array<std::uint64_t, 2> excitation_seeds{};
  std::array<std::uint64_t, 2> noise_seeds{};
};

// Draws a case from a seed (the effect is the caller's: a benchmark runs N draws per effect).
[[nodiscard]] Draw make_draw(std::uint64_t seed, Effect effect);
// The form with its numbers at the draw's magnitudes ("leakage:highpass tau=2.1e+03 s").
[[nodiscard]] std::string describe(const Draw& draw);

struct Recording {
  double sample_time{0.0};
  std::vector<double> e{}, d{}, s{}, t{}, temp{};
};

struct RecordOptions {
  int excitation{0};  // 0: identification, 1: validation
  bool effect{true};  // false: the same recording without the effect (the clean base)
  double scale{1.0};  // multiplies the draw's magnitudes
  bool noise{true};   // false: noise-free channels (generator tests)
};

// The recording of a draw; deterministic in (draw, options). With effect false or a zero scale
// the excitation, temperature and noise are the same as with the effect.
[[nodiscard]] Recording record(const Draw& draw, const RecordOptions& options);

// The channel sampled `samples` late (cubic interpolation; the first value held before the
// start). Exposed for the generator tests.
[[nodiscard]] std::vector<double> delayed(const std::vector<double>& x, double samples);

// Uniform in [0, 1) and standard normal from the engine's raw output (portable).
[[nodiscard]] double uniform01(std::mt19937_64& rng) noexcept;
[[nodiscard]] double normal(std::mt19937_64& rng) noexcept;

}  // namespace selfsense::independent
