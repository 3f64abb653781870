// Hysteresis-creep operator (paper eq. 26-29, in Kuhnen's modified-PI form) and its inverse.
//
//   Gamma[x] = S[ H[x] + K[x] ]
//   H[x] = sum_{i=0..n} w_i p_i            PI operator, p_0 = x, thresholds 0 = r_0 < ... < r_n
//          + sum_h c_h max(0, p_{r_h} - b_h)  optional hinges (play_hinges.hpp): Preisach class
//   K[x] = sum_{i,j} c_ij z_ij             creep elements: lag lambda_j on the play of threshold
//                                          r_i (ThresholdCreep), c_ij >= 0
//   S                                      dead-zone superposition (asymmetry, saturation)
// The paper's K = L[H[x]] (eq. 28) is the rank-one case c_ij = w_i c_j (with_nonlinear_creep()).
// H and K share one play bank: the union of their thresholds (and the hinges').
//
// Inverse, one sample at a time (inverse_step). With a_j = 1 - exp(-lambda_j Ts) the lags give
//   K[x][k] = sum_i b_i p_i[k] + sum_{i,j} c_ij (1 - a_j) z_ij[k-1],   b_i = sum_j c_ij a_j,
// so at sample k, H + K is a PI operator with weights w_i + b_i (fixed for a fixed Ts) plus a
// known carry from the previous lag states. Hence
//   v = S^-1[y],  x = H~^-1[v - carry],  H~ = PI(r, w + b),
// all closed form; H~^-1 is evaluated from the current forward play states (no separate
// inverse state that could drift). The weights keep H~ invertible because c_ij >= 0.
// With hinges H~ is no longer a PI operator: the sample's output is still piecewise linear in
// x (each play moves with x or holds, each hinge is on or off), so x is solved for by a
// safeguarded Newton iteration on that function (bisection inside a bracket when Newton
// leaves it), which lands exactly once it reaches the right piece: each evaluation also gives
// the slopes on both sides of x and the kinks around it, so a step that stays in its piece is
// the root (one evaluation for most samples, starting at the previous sample's root); the root
// is unique while H~ increases in x, and when hinges bend it back, a root next to the PI part's
// inverse is taken.
//
// The hinges of one play add a piecewise-linear function of its output p, g(p) = sum_h c_h
// max(0, p - b_h), precomputed as segments: with the play's levels sorted, b_(1) <= ... <=
// b_(m), on segment k (k levels below p)
//   g(p) = g_k + s_k (p - b_(k)),   s_k = sum_{j<=k} c_(j),   g_k = g(b_(k))   (g_0 = s_0 = 0)
// Each play keeps the segment its output is on and its term g(p), both looked up again only
// when the play moves (a play moves by at most the input's step, so its segment usually stays
// or moves by one), which makes a forward step and each trial of the inverse O(plays) whatever
// the number of hinges: one table read and one multiply-add per moving play instead of one per
// hinge. Results agree with the per-hinge sum to
// rounding (tests/operators/hinge_table_test.cpp holds them to 1e-12 relative).
//
// step() and inverse_step() are real-time safe: O(n_plays + n_creep + n_deadzones), plus a
// segment moved per level a play's output crosses (the inverse with hinges a bounded number of
// such evaluations), no allocation, no exceptions.
#pragma once

#include <cstddef>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "selfsense/operators/dead_zone_superposition.hpp"
#include "selfsense/operators/linear_creep.hpp"
#include "selfsense/operators/play_hinges.hpp"
#include "selfsense/operators/prandtl_ishlinskii.hpp"
#include "selfsense/operators/threshold_creep.hpp"

namespace selfsense::operators {

class HysteresisCreep final {
 public:
  struct Params {
    PrandtlIshlinskii::Params hysteresis{};
    DeadZoneSuperposition::Params superposition{};  // default: identity
    ThresholdCreep::Params creep{};                 // default: no creep
    PlayHinges hinges{};                            // default: none (a PI operator)

    [[nodiscard]] bool is_valid(std::string* why) const;
  };

  // Paper eq. (28): K = L[H[x]], i.e. creep weights c_ij = w_i c_j on the PI thresholds.
  // Throws ParameterError if a PI weight is negative (creep weights must stay >= 0).
  [[nodiscard]] static Params with_nonlinear_creep(const PrandtlIshlinskii::Params& hysteresis,
                                                   const DeadZoneSuperposition::Params& shape,
                                                   const LinearCreep::Params& creep);

  // Throws ParameterError naming the offending parameter. State: everything at 0.
  HysteresisCreep(Params params, double sample_time);

  [[nodiscard]] const Params& params() const noexcept { return params_; }
  [[nodiscard]] double sample_time() const noexcept { return sample_time_; }

  // Forward: input x in, output Gamma[x] out.
  double step(double x) noexcept;
  void apply(std::span<const double> x, std::span<double> y) noexcept;
  // The input x that would make this sample's output equal y. Does not change the state
  // (the non-const is for a scratch buffer and, with hinges, where the next solve starts).
  [[nodiscard]] double input_for(double y) noexcept;
  // Inverse: input_for(y), then advance with that x, so forward and inverse share one state.
  double inverse_step(double y) noexcept;
  void apply_inverse(std::span<const double> y, std::span<double> x) noexcept;
  [[nodiscard]] double output() const noexcept;

  // State: the shared play bank (one value per union threshold), then the creep lags
  // (row-major, creep thresholds x eigenvalues).
  [[nodiscard]] std::span<const double> state() const noexcept { return state_; }
  void set_state(std::span<const double> state) noexcept;
  // Equilibrium at a constant input x (all plays and lags at x).
  void reset(double x = 0.0) noexcept;
  // Remanent state: the plays after the input went through these turning points (from rest at
  // the first), every creep lag settled at its play. Empty: reset(0).
  void set_history(std::span<const double> turning_points) noexcept;
  // Union of hysteresis and creep thresholds, r_0 = 0 first: what the play states refer to.
  [[nodiscard]] std::span<const double> play_thresholds() const noexcept { return thresholds_; }

 private:
  [[nodiscard]] std::size_t play_count() const noexcept { return thresholds_.size(); }
  [[nodiscard]] std::span<double> plays() noexcept { return std::span(state_).first(play_count()); }
  [[nodiscard]] std::span<double> lags() noexcept {
    return std::span(state_).subspan(play_count());
  }
  [[nodiscard]] double inner_step(double x) noexcept;  // H[x] + K[x], advancing the state
  // sum_i g_i(p_i) for the current state.
  [[nodiscard]] double hinge_sum() const noexcept;
  // The segment of every play from scratch (after the state was set).
  void locate_segments() noexcept;
  // g_i(v) with k levels of play i below v.
  [[nodiscard]] double hinge_value(std::size_t i, std::size_t k, double v) const noexcept {
    const std::size_t at = i * hinge_stride_ + k;
    return segment_values_[at] + segment_slopes_[at] * (v - segment_anchors_[at]);
  }
  // H~ at input x from the current state, without advancing, and the linear pieces on either
  // side of x.
  struct Trial {
    double value;       // H~ at x
    double slope_down;  // dH~/dx on [below, x]
    double slope_up;    // dH~/dx on [x, above]
    double below;       // the nearest kinks below and above x
    double above;
  };
  // Non-const: each play's term goes to scratch_ (the PI inverse's, unused with hinges).
  [[nodiscard]] Trial trial_inner(double x) noexcept;
  // H~[x] = target, the iteration started at `start`.
  [[nodiscard]] double solve_inner(double target, double start) noexcept;

  Params params_{};
  double sample_time_{0.0};
  DeadZoneSuperposition shape_{};
  DeadZoneSuperposition shape_inverse_{};
  std::vector<double> thresholds_{};          // union, r_0 = 0 first
  std::vector<double> hysteresis_weights_{};  // w on the union (0 where only creep has a play)
  std::vector<std::size_t> creep_rows_{};     // play index of each creep threshold
  std::vector<double> creep_weights_{};       // c_ij, row-major
  std::vector<double> creep_gains_{};         // a_j per element, row-major
  std::vector<double> carry_weights_{};       // c_ij (1 - a_j), row-major
  std::vector<double> inverse_thresholds_{};  // r' of H~^-1
  std::vector<double> inverse_weights_{};     // w' of H~^-1
  std::vector<double> effective_weights_{};   // w + b
  std::vector<double>
      scratch_{};  // inverse play states, or with hinges each play's term; sized once
  std::vector<std::size_t> hinge_rows_{};  // play index of each hinge
  // Segments, play by play, hinge_stride_ = (most hinges on one play) + 1 entries each.
  std::size_t hinge_stride_{0};
  std::vector<double> hinge_levels_{};       // ascending, then +inf (fewer hinges; the sentinel)
  std::vector<double> segment_slopes_{};     // s_k
  std::vector<double> segment_anchors_{};    // b_(k) (0 for k = 0)
  std::vector<double> segment_values_{};     // g_k
  std::vector<std::size_t> segments_{};      // per play: its levels below its output (state)
  std::vector<double> hinge_terms_{};        // per play: g_i(p_i) (state)
  std::vector<std::size_t> hinged_plays_{};  // the plays with hinges, ascending
  double scale_{1.0};                        // input scale of the inverse's first step
  std::vector<double> state_{};              // plays, then lags
  // The previous sample's inverse with hinges: where the next solve starts. Not the input
  // applied (state_[0]): in a loop the feedback moves that far from the feedforward's root.
  double last_root_{std::numeric_limits<double>::quiet_NaN()};
};

// Feedforward inverse compensator (the paper's reference [11]): desired output in, actuator
// input out, so that the modelled actuator follows the desired trajectory. The input is limited
// to [input_min, input_max] (the amplifier's range); when it saturates (or the desired output
// is NaN), the internal model advances with the limited input so its state stays that of the
// real actuator, and the saturation is counted.
class HysteresisCreepCompensator final {
 public:
  // Throws ParameterError unless input_min < input_max.
  HysteresisCreepCompensator(HysteresisCreep model, double input_min, double input_max);

  // Real-time safe.
  double step(double desired_output) noexcept;
  void apply(std::span<const double> desired, std::span<double> input) noexcept;

  [[nodiscard]] const HysteresisCreep& model() const noexcept { return model_; }
  [[nodiscard]] HysteresisCreep& model() noexcept { return model_; }
  [[nodiscard]] std::size_t saturation_count() const noexcept { return saturations_; }

 private:
  HysteresisCreep model_;
  double input_min_{0.0};
  double input_max_{0.0};
  std::size_t saturations_{0};
};

}  // namespace selfsense::operators
