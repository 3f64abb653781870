// The simulated piezo stack: a plant richer than the project's models, for tests, data
// generation, demos and the daemon's simulated backend. Configured by PlantConfig
// (config.hpp); every effect is switchable.
//
// One step at sample k (Ts = 1 / sample_rate_hz, t = k Ts):
//   1. amplifier:  u = Amp[E_cmd h]                         (range, slew, current limit)
//   2. field:      E = u / h
//   3. polarisation: p = Preisach[E]                         (hysteresis)
//   4. free response, coefficients c(temp, T, t) at the input temperature (plus the
//      self-heating's rise, HeatingConfig), the stack stress T and the plant's age t (aging:
//      AgingConfig):
//        S_i = d(T) E + a_S(T) (p - p0),  S_free = S_i + Creep_S[S_i]
//   5. mechanics:  x = MSD[x_eq(S_free)],  S = x / L,  T = (S - S_free) / s^E
//      Steps 4-5 make T a function f of the T that the coefficients see; the plant solves
//      T = f(T) at every sample (f is affine in T, so two trial evaluations give the root), so
//      S, T and D of one sample satisfy the constitutive law at one and the same stress.
//   6. charge:     D_i = eps(E, T) E + a_D(T) (p - p0),  D = D_i + Creep_D[D_i] + d(T) T,
//                  q = n A_el (D - D(0)),  q_amp = ChargeAmp[q + q_leak] (q_leak: the
//                  insulation leakage's charge, AgingConfig)
//   7. sensors:    E_meas = Ch_E[E],  D_meas = Ch_D[q_amp / (n A_el)],  then faults
// Randomness comes from one std::mt19937_64 seeded with PlantConfig::seed.
//
// Real-time safety: step(), run(), inject(), clear_faults(), save() and restore() neither
// allocate, lock, throw nor do I/O. The constructor allocates (the Everett table) and throws
// std::invalid_argument for an invalid configuration.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "selfsense/plant/amplifier.hpp"
#include "selfsense/plant/charge_amplifier.hpp"
#include "selfsense/plant/config.hpp"
#include "selfsense/plant/creep_bank.hpp"
#include "selfsense/plant/faults.hpp"
#include "selfsense/plant/mechanics.hpp"
#include "selfsense/plant/preisach.hpp"
#include "selfsense/plant/random.hpp"
#include "selfsense/plant/sensor_channel.hpp"
#include "selfsense/plant/status.hpp"

namespace selfsense::plant {

struct StepInput {
  double e_cmd_v_per_m{0.0};  // commanded field (the amplifier's command times 1/h)
  double force_n{0.0};        // external force added to mechanics.load_force_n
  double temp_degc{25.0};
};

struct StepOutput {
  double t_s{0.0};
  // What a controller sees (delay, noise, ADC, leakage, drift, faults).
  double e_meas_v_per_m{0.0};
  double d_meas_c_per_m2{0.0};
  // The truth, for reference columns. The terminal values follow from the field values by the
  // geometry exactly: u = E h, q = D n A_el, x = S L, f = T A_mech.
  double e_v_per_m{0.0};
  double d_c_per_m2{0.0};  // relative to the charge at reset
  double s{0.0};
  double t_pa{0.0};
  double u_v{0.0};
  double q_c{0.0};  // stack charge, relative to the charge at reset
  double x_m{0.0};
  double f_n{0.0};           // force in the stack, T A_mech
  double temp_degc{0.0};     // the stack's: the input's plus the self-heating's rise
  double polarisation{0.0};  // Preisach output p
  double q_amp_c{0.0};       // charge amplifier output (leakage, offset), before delay and ADC
  double latency_s{0.0};     // > 0 for a late sample
  std::uint32_t status{kStatusOk};
};

class Plant final {
 public:
  // Everything that evolves; a value type. Valid only with the plant that produced it.
  struct State {
    std::int64_t sample{0};
    PreisachState preisach{};
    CreepBank creep_s{};
    CreepBank creep_d{};
    Mechanics mechanics{};
    Amplifier amplifier{};
    ChargeAmplifier charge_amplifier{};
    SensorChannel channel_e{};
    SensorChannel channel_d{};
    FaultTable faults{};
    Random random{1};
    double p0{0.0};
    double d0{0.0};
    double t_prev_pa{0.0};
    double u_prev_v{0.0};
    double q_prev_c{0.0};
    double capacitance_est_f{0.0};
    double q_leak_c{0.0};        // charge through the insulation leakage (AgingConfig)
    double heating_rise_k{0.0};  // self-heating over the input temperature (HeatingConfig)
    StepOutput last{};
  };

  explicit Plant(const PlantConfig& config);

  // Back to t = 0 with the configured seed and fault schedule, at E = 0, T at the static load.
  void reset();
  StepOutput step(const StepInput& input) noexcept;
  // Steps once per input; out.size() must equal in.size().
  void run(std::span<const StepInput> in, std::span<StepOutput> out) noexcept;

  // Fault injection, times in samples from t = 0; false when the fault table is full.
  bool inject(FaultKind kind, Channel channel, std::int64_t start_sample,
              std::int64_t duration_samples, double late_by_s = 0.0) noexcept;
  void clear_faults() noexcept { state_.faults.clear(); }

  [[nodiscard]] const State& save() const noexcept { return state_; }
  void restore(const State& state) noexcept { state_ = state; }

  [[nodiscard]] const PlantConfig& config() const noexcept { return config_; }
  [[nodiscard]] const Derived& derived() const noexcept { return derived_; }
  [[nodiscard]] double sample_time_s() const noexcept { return ts_; }

 private:
  [[nodiscard]] double capacitance_linear(double e) const noexcept;

  PlantConfig config_;
  Derived derived_{};
  double ts_{};
  double heating_gain_{};  // 1 - exp(-Ts / tau) (HeatingConfig)
  std::unique_ptr<const EverettTable> everett_{};
  State state_{};
};

// Runs a fresh plant over the inputs (allocates the result; not real-time).
[[nodiscard]] std::vector<StepOutput> simulate(const PlantConfig& config,
                                               std::span<const StepInput> inputs);

}  // namespace selfsense::plant
