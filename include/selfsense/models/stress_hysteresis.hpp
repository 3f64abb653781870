// Stress-dependent hysteresis: the vectorial case of section 3.3 that the paper leaves as
// future work, in a form that stays linear in its parameters. With q(E) the play columns of the
// field history and, optionally, the creep lags on some of them (operators/regressor_stream.hpp:
// H[E] + K[E] = W . q; lag j of play i: z[k] = z[k-1] + a_j (p_i[k] - z[k-1]), a_j = 1 -
// exp(-lambda_j Ts)),
//   D = W0 . q + T (W1 . q) + d1 T + d2 T^2 + D0       sensor side
//   S = A0 . q + T (A1 . q) + s1 T + s2 T^2 + S0       actuator side
// so coupling, permittivity and hysteresis amplitude all change with stress. D is no longer
// affine in T but quadratic, so reconstruction solves, at every sample,
//   c T^2 + b T + (a - D_measured) = 0,   a = W0.q + D0,  b = W1.q + d1,  c = d2
// in closed form. dD/dT = b + 2 c T is linear in T, so D is strictly monotone over the
// identified stress range [stress_min, stress_max] exactly when the vertex -b / 2c lies outside
// it (existence and uniqueness of the inverse, eq. 3): then the solution is the root on that
// branch, T = (-b + s sqrt(b^2 - 4 c (a - D))) / 2c with s the sign of dD/dT on the range
// (evaluated in the cancellation-free form). Reported, never hidden: kNotMonotone when the vertex
// is inside the range, kNoSolution when no real root exists (the estimate is then the vertex,
// the stress closest to reproducing D).
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "selfsense/models/sample_status.hpp"
#include "selfsense/operators/regressor_stream.hpp"

namespace selfsense::models {

struct StressHysteresisSide {
  std::vector<double> base{};    // W0 on the play columns
  std::vector<double> stress{};  // W1: change of the hysteresis per Pa
  double linear{0.0};            // d1 (or s1)
  double quadratic{0.0};         // d2 (or s2)
  double offset{0.0};

  // y at the play columns q and stress t. Real-time safe.
  [[nodiscard]] double evaluate(std::span<const double> q, double t) const noexcept;
};

struct StressHysteresisModel {
  double sample_time{0.0};
  // Plays, and creep lags (eigenvalues on creep_rows) if any; no hinges. The gains a_j follow
  // from the eigenvalues and sample_time (with_creep_gains), so a model runs at any rate.
  operators::OperatorBasis basis{};
  std::vector<double> history{};  // field turning points before the first sample
  std::optional<StressHysteresisSide> sensor{};
  std::optional<StressHysteresisSide> actuator{};
  double stress_min{0.0};  // reconstruction bracket [Pa]
  double stress_max{0.0};

  // Thresholds start at 0 and increase, creep rows name plays in increasing order and
  // eigenvalues are positive, every side has one weight per column (plays, then lags), the
  // bracket is ordered; names the field ("vectorial.sensor.base has 3 elements ...").
  [[nodiscard]] bool is_valid(std::string* why) const;
};

// The model with basis.gains derived from its eigenvalues and sample_time (a_j above).
[[nodiscard]] StressHysteresisModel with_creep_gains(StressHysteresisModel model);

// Per-sample forward model (E, T -> D, S); allocation-free after construction.
class StressHysteresisForward final {
 public:
  struct Output {
    double sensed{0.0};  // D; NaN without a sensor side
    double strain{0.0};  // S; NaN without an actuator side
  };
  explicit StressHysteresisForward(StressHysteresisModel model);
  StressHysteresisForward(const StressHysteresisForward&) = delete;
  StressHysteresisForward& operator=(const StressHysteresisForward&) = delete;
  StressHysteresisForward(StressHysteresisForward&&) = delete;
  StressHysteresisForward& operator=(StressHysteresisForward&&) = delete;
  ~StressHysteresisForward() = default;
  Output step(double e, double t) noexcept;
  [[nodiscard]] const StressHysteresisModel& model() const noexcept { return model_; }
  [[nodiscard]] const operators::RegressorStream& stream() const noexcept { return stream_; }
  [[nodiscard]] operators::RegressorStream& stream() noexcept { return stream_; }
  // The field history (plays); saved into and restored from caller buffers, no allocation.
  [[nodiscard]] std::size_t state_size() const noexcept { return stream_.state_size(); }
  void save_state(std::span<double> out) const noexcept { stream_.save_state(out); }
  void restore_state(std::span<const double> in) noexcept { stream_.restore_state(in); }

 private:
  StressHysteresisModel model_;  // the stream below points into it: not copyable
  operators::RegressorStream stream_;
};

// Per-sample reconstruction; allocation-free after construction.
class StressHysteresisReconstructor final {
 public:
  struct Estimate {
    double stress{0.0};
    double strain{0.0};  // NaN without an actuator side
    SampleStatus status{SampleStatus::kOk};
  };
  // Throws std::invalid_argument without a sensor side. Keeps its own copy of the model.
  explicit StressHysteresisReconstructor(StressHysteresisModel model);
  StressHysteresisReconstructor(const StressHysteresisReconstructor&) = delete;
  StressHysteresisReconstructor& operator=(const StressHysteresisReconstructor&) = delete;
  StressHysteresisReconstructor(StressHysteresisReconstructor&&) = delete;
  StressHysteresisReconstructor& operator=(StressHysteresisReconstructor&&) = delete;
  ~StressHysteresisReconstructor() = default;
  Estimate step(double e, double d) noexcept;
  [[nodiscard]] std::size_t state_size() const noexcept { return stream_.state_size(); }
  void save_state(std::span<double> out) const noexcept { stream_.save_state(out); }
  void restore_state(std::span<const double> in) noexcept { stream_.restore_state(in); }
  // How often each status occurred.
  [[nodiscard]] const StatusCounts& status_counts() const noexcept { return counts_; }
  [[nodiscard]] const StressHysteresisModel& model() const noexcept { return model_; }
  [[nodiscard]] const operators::RegressorStream& stream() const noexcept { return stream_; }
  [[nodiscard]] operators::RegressorStream& stream() noexcept { return stream_; }

 private:
  StressHysteresisModel model_;  // the stream below points into it: not copyable
  operators::RegressorStream stream_;
  StatusCounts counts_{};
};

}  // namespace selfsense::models
