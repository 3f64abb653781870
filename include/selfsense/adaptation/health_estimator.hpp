// The transducer's health from the signals the loop measures anyway, E [V/m] and D [C/m^2]
// (issue 24 item 3, docs/health.md): the capacitance, the dissipation per drive cycle, the
// loss of polarisation they imply, the leakage from holds, each with a slow value and a slope
// (trend_filter.hpp).
//
// Reversals: the field's running extreme (E_x, D_x) is followed; once E has moved back from it
// by delta = reversal_field_v_per_m, a reversal is declared at the present sample k. The
// capacitance there is the first slope of D after the reversal:
//   C_rev = (D[k] - D_x) / (E[k] - E_x)                                            [F/m]
// (a Preisach loop leaves a reversal with zero slope, so this is the permittivity and what
// moves with it: the permittivity seen as dD/dE on small reversals, docs/health.md).
//
// Dissipation: a full cycle runs from one reversal at a minimum to the next (samples a..b). The
// loop area, closed by the chord from b back to a:
//   W = sum_{k=a+1..b} (E[k] + E[k-1]) / 2 (D[k] - D[k-1]) + (E[b] + E[a]) / 2 (D[a] - D[b])
//                                                                                  [J/m^3]
// the energy lost per cycle and unit volume (a leakage current adds its Joule heat). The
// cycle's capacitance C is the mean of its two reversals' C_rev.
//
// Loss of polarisation: once cycles with the same field extremes (within span_tolerance of the
// span) have run for settle_s (the creep settles after the drive starts or changes), the next
// baseline_cycles set the baseline (C_b, W_b, E_min,b, E_max,b), the stack as new.
// A later cycle is compared with it; the capacitance's change is read as a temperature rise
// and the loop's expected change at that temperature is taken out:
//   rise = (C / C_b - 1) / capacitance_per_k                                       [K]
//   loss = (1 - rho / (1 + dissipation_per_k rise)) / depolarisation_sensitivity   [1]
// with rho the loop's change against the baseline for the same drive:
//   rho = (W / W_p) / (W_b / W_p,b)   model_reference, with the model's prediction: W_p is the
//                                     loop area of the predicted D (the `predicted` input: the
//                                     model's D for the measured field path, as identified) over
//                                     the same samples, so a cycle is compared whatever its
//                                     extremes, once its span is within max_span_change of the
//                                     baseline's (a closed position loop raises the field as
//                                     the stack ages: docs/health.md)
//   rho = W / W_b                     otherwise, only a cycle with the baseline's extremes
//                                     (within span_tolerance)
// Warming raises C and narrows the loop; losing polarisation narrows the loop alone on a free
// stack (sensitivity 1). On a load spring the stress follows the field and takes part of the
// reversal slope (about -d^2 k_load / (1 + r)), which shrinks with the polarisation too, so the
// compensated loop sees only part of the loss: the sensitivity is measured (docs/health.md). A
// cycle that is not compared is measured (C, W) all the same.
//
// Leakage: a hold is a run of samples whose field stays within hold_field_v_per_m of its first
// sample. After hold_settle_s (the fast creep), each window of hold_window_s gives the slope of
// D by least squares over its samples (t from the window's start):
//   dD/dt = (n sum t D - sum t sum D) / (n sum t^2 - (sum t)^2)                    [A/m^2]
//   sigma = (dD/dt) / mean(E)     when |mean(E)| >= min_hold_field_v_per_m          [S/m]
// the leakage conductivity, and the resistivity rho = 1 / sigma [Ohm m] (the stack's
// resistance R = rho h / (n A), its time constant R C_stack = rho eps). The slow creep of D
// still moving at the hold adds to the slope, so rho is a lower bound on a stack that creeps.
//
// A rejected sample (accepted false) ends the cycle and the hold in progress: neither is
// counted. Time is the sample count times the sample time.
//
// Real-time safe after construction: step(), figures(), save_state(), restore_state() are
// noexcept and allocate nothing.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string>

#include "selfsense/adaptation/trend_filter.hpp"

namespace selfsense::adaptation {

struct HealthEstimatorConfig {
  double reversal_field_v_per_m{50.0e3};  // delta: a reversal, and the capacitance's step [V/m]
  double settle_s{100.0};                 // cycles with the same extremes skipped first [s]
  std::uint32_t baseline_cycles{20};      // then the cycles that set the baseline
  double span_tolerance{0.05};            // extremes within this share of the span: comparable
  double hold_field_v_per_m{5.0e3};       // a hold: E within this of its first sample [V/m]
  double hold_settle_s{2.0};              // skipped at a hold's start (fast creep) [s]
  double hold_window_s{5.0};              // one leakage estimate per window [s]
  double min_hold_field_v_per_m{2.0e5};   // leakage only from holds at |E| >= this [V/m]
  double trend_time_s{20.0};              // tau1: the slow value [s]
  double slope_time_s{600.0};             // tau2 > tau1: the slope [s]
  // Relative changes per K of the two observables (measured on the simulated stack,
  // docs/health.md): the reversal capacitance and the loop area.
  double capacitance_per_k{4.0e-3};
  double dissipation_per_k{-4.0e-3};
  // The compensated loop's relative change per relative loss of polarisation [1]: 1 on a free
  // stack whose loop area is all polarisation (header comment).
  double depolarisation_sensitivity{1.0};
  // Compare each cycle's loop with the model's predicted loop for the same field path when the
  // caller gives a prediction (header comment); cycles whose span differs from the baseline's
  // by more than max_span_change (relative) are not compared.
  bool model_reference{true};
  double max_span_change{0.5};

  // Every value finite; fields, times positive (settle_s, hold_settle_s >= 0);
  // slope_time_s > trend_time_s; baseline_cycles
  // >= 1; span_tolerance in (0, 1); capacitance_per_k non-zero; depolarisation_sensitivity in
  // (0, 2]; max_span_change in (0, 1]. *why names the key under
  // `prefix` ("health.trend_time_s: must be > 0").
  [[nodiscard]] bool is_valid(const std::string& prefix, std::string* why) const;
  friend bool operator==(const HealthEstimatorConfig&, const HealthEstimatorConfig&) = default;
};

// What the estimator holds now: slow values, slopes per hour, counts. A value not yet measured
// is NaN (has_* false).
struct HealthFigures {
  bool has_capacitance{false};
  double capacitance_f_per_m{0.0};  // slow C [F/m]
  double capacitance_per_h{0.0};    // its slope relative to it [1/h]
  bool has_dissipation{false};
  double dissipation_j_per_m3{0.0};  // slow W per cycle [J/m^3]
  double dissipation_per_h{0.0};     // relative slope [1/h]
  bool baseline_ready{false};
  bool has_depolarisation{false};
  double depolarisation{0.0};        // slow loss of polarisation [1] (0.05: 5 % lost)
  double depolarisation_per_h{0.0};  // its slope [1/h]
  bool has_leakage{false};
  double leakage_conductivity_s_per_m{0.0};  // slow sigma [S/m]
  double leakage_conductivity_per_h{0.0};    // its slope [S/m per h]
  double leakage_resistivity_ohm_m{0.0};     // 1 / sigma; +inf when sigma <= 0
  std::uint64_t cycles{0};                   // full cycles measured
  std::uint64_t compared_cycles{0};          // of them compared with the baseline
  std::uint64_t holds{0};                    // leakage windows measured
};

class HealthEstimator final {
 public:
  // Throws std::invalid_argument (naming the key) on an invalid configuration or a
  // non-positive sample time.
  HealthEstimator(const HealthEstimatorConfig& config, double sample_time_s);

  // One sample; returns true when it completed a cycle. predicted: the model's D [C/m^2] for
  // the field path (NaN: none; the cycles are then compared at the baseline's extremes only).
  bool step(double field, double sensed, double predicted, bool accepted) noexcept;
  bool step(double field, double sensed, bool accepted) noexcept {
    return step(field, sensed, kNoPrediction, accepted);
  }
  static constexpr double kNoPrediction{std::numeric_limits<double>::quiet_NaN()};

  [[nodiscard]] HealthFigures figures() const noexcept;
  [[nodiscard]] const TrendFilter& capacitance() const noexcept { return capacitance_; }
  [[nodiscard]] const TrendFilter& dissipation() const noexcept { return dissipation_; }
  [[nodiscard]] const TrendFilter& depolarisation() const noexcept { return depolarisation_; }
  [[nodiscard]] const TrendFilter& conductivity() const noexcept { return conductivity_; }
  [[nodiscard]] const HealthEstimatorConfig& config() const noexcept { return config_; }
  [[nodiscard]] double time_s() const noexcept;

  // The learned baseline, trends and counts (the cycle and hold in progress start anew).
  static constexpr std::size_t kStateSize{12 + 4 * TrendFilter::kStateSize};
  [[nodiscard]] static constexpr std::size_t state_size() noexcept { return kStateSize; }
  void save_state(std::span<double> out) const noexcept;
  void restore_state(std::span<const double> in) noexcept;

 private:
  void follow_reversals(double e, double d, double p) noexcept;
  void on_reversal(bool at_minimum, double e, double d, double p, double extreme_e,
                   double c_rev) noexcept;
  void finish_cycle(double e, double d, double p) noexcept;
  void follow_hold(double e, double d) noexcept;
  void drop() noexcept;

  HealthEstimatorConfig config_;
  double ts_{0.0};
  std::uint64_t samples_{0};
  // Reversals: direction (+1 rising, -1 falling, 0 not yet known), the running extreme.
  bool has_last_{false};
  int direction_{0};
  double first_e_{0.0};
  double extreme_e_{0.0};
  double extreme_d_{0.0};
  double last_e_{0.0};
  double last_d_{0.0};
  double last_p_{0.0};  // the prediction
  // The cycle in progress.
  bool in_cycle_{false};
  bool top_seen_{false};
  double area_{0.0};
  double start_e_{0.0};
  double start_d_{0.0};
  double area_p_{0.0};  // the predicted loop's area so far (NaN once a prediction is missing)
  double start_p_{0.0};
  double cycle_min_e_{0.0};
  double cycle_max_e_{0.0};
  double cycle_c_sum_{0.0};
  // Baseline: the extremes followed since base_start_s_, then the averaged cycles.
  bool has_extremes_{false};
  double base_start_s_{0.0};
  double base_n_{0.0};
  double base_c_{0.0};
  double base_w_{0.0};
  double base_wp_{0.0};  // the predicted loop's; <= 0: no prediction in the baseline
  double base_min_{0.0};
  double base_max_{0.0};
  // The hold in progress and its window's sums.
  bool in_hold_{false};
  double hold_e_{0.0};
  double hold_start_s_{0.0};
  double window_start_s_{0.0};
  double n_{0.0};
  double st_{0.0};
  double stt_{0.0};
  double sd_{0.0};
  double std_{0.0};
  double se_{0.0};
  TrendFilter capacitance_;
  TrendFilter dissipation_;
  TrendFilter depolarisation_;
  TrendFilter conductivity_;
  std::uint64_t cycles_{0};
  std::uint64_t compared_{0};
  std::uint64_t holds_{0};
};

}  // namespace selfsense::adaptation
