// Play (backlash) and stop operators, the elementary hysteresis operators.
//
// Play with threshold r >= 0 on input x (any unit; the output has the unit of x):
//   y[k] = max(x[k] - r, min(x[k] + r, y[k-1]))
// The previous output y[k-1] is the whole state; y[-1] is settable, so a remanent state after
// power-up can be represented. Rate-independent: only the order of input extrema matters.
//
// Stop with threshold r is the dual: e[k] = x[k] - y[k] with y the play above, so
//   e[k] = max(-r, min(r, e[k-1] + x[k] - x[k-1])),  |e| <= r.
//
// step() is real-time safe: O(1), no allocation, no exceptions.
#pragma once

#include <algorithm>
#include <span>

namespace selfsense::operators {

class PlayOperator final {
 public:
  // Throws ParameterError unless threshold is finite and >= 0.
  explicit PlayOperator(double threshold, double initial_output = 0.0);

  [[nodiscard]] double threshold() const noexcept { return threshold_; }
  [[nodiscard]] double output() const noexcept { return output_; }
  void set_output(double output) noexcept { output_ = output; }

  double step(double x) noexcept {
    output_ = std::min(std::max(output_, x - threshold_), x + threshold_);
    return output_;
  }

  // Batch form: y[k] = step(x[k]); x and y may alias; sizes must match.
  void apply(std::span<const double> x, std::span<double> y) noexcept;

 private:
  double threshold_{0.0};
  double output_{0.0};
};

class StopOperator final {
 public:
  // Throws ParameterError unless threshold is finite and >= 0. The state is the pair
  // (last input, last output), i.e. the dual play sits at last_input - last_output.
  explicit StopOperator(double threshold, double last_input = 0.0, double last_output = 0.0);

  [[nodiscard]] double threshold() const noexcept { return play_.threshold(); }
  [[nodiscard]] double output() const noexcept { return last_input_ - play_.output(); }
  void set_state(double last_input, double last_output) noexcept {
    last_input_ = last_input;
    play_.set_output(last_input - last_output);
  }

  double step(double x) noexcept {
    last_input_ = x;
    return x - play_.step(x);
  }

  void apply(std::span<const double> x, std::span<double> y) noexcept;

 private:
  PlayOperator play_;
  double last_input_{0.0};
};

}  // namespace selfsense::operators
