// Setpoint waveforms: sine, triangle, square, staircase and an arbitrary table, each with
// amplitude, offset, period, start phase and a repeat count. Sample time Ts [s] fixed at
// construction.
//
// Output, in the setpoint's unit [x]:   w[k] = offset + amplitude * shape(p[k])
// with the position in the period p in [0, 1) and the unit shapes
//   sine       sin(2 pi p)
//   triangle   4p on [0, 1/4), 2 - 4p on [1/4, 3/4), 4p - 4 on [3/4, 1)   (in phase with sine)
//   square     +1 on [0, 1/2), -1 on [1/2, 1)
//   staircase  levels[floor(p L)]: L levels, each held for `dwell` [s]
//   table      linear interpolation of (t_i, v_i) at t = t_0 + p (t_{n-1} - t_0); the times are
//              given, or t_i = i * table_dt. The table is copied at construction and never
//              reallocated.
// Period: 1 / frequency; for staircase and table a frequency of 0 keeps the natural period
// (L * dwell, t_{n-1} - t_0) and a frequency > 0 time-scales them.
//
// Timing from an integer sample count, never from accumulated float time: with P = period / Ts
// samples (snapped to a whole number when within 1e-9 of one), n samples since the start and
// start phase phi [cycles],
//   x[k] = phi P + n,   p[k] = (x - floor(x / P) P) / P,   cycles played = n / P.
// When P is whole the cycle count and the positions are exact for any n below 2^53 (about
// 14000 years at 20 kHz): nothing drifts. Otherwise the error is one rounding of x (1e-7 samples
// after a day at 20 kHz) and does not grow with time.
//
// set_frequency() changes the period phase-continuously: the position in the period is kept and
// counting restarts from it. With repeats > 0, done() turns true once that many periods have
// played; the output then holds the waveform's value at the end of the last period (the
// table's last value, the last stair, offset for sine and triangle, the low level of a square).
//
// Real-time safe: step(), set_frequency(), restart(), save_state(), restore_state(). The
// constructor allocates (it copies the table) and throws ParameterError naming the parameter.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace selfsense::control {

class WaveGenerator final {
 public:
  enum class Shape : std::uint8_t { kSine, kTriangle, kSquare, kStaircase, kTable };

  struct Config {
    Shape shape{Shape::kSine};
    double amplitude{1.0};         // [x], finite
    double offset{0.0};            // [x], finite
    double frequency{0.0};         // [Hz]: > 0 for sine/triangle/square; staircase, table: >= 0
    double phase{0.0};             // start position in the period [cycles], in [0, 1)
    std::uint64_t repeats{0};      // periods to play; 0 = forever
    std::vector<double> levels{};  // staircase: unit levels, in order
    double dwell{0.0};             // staircase: [s] > 0 per level at the natural period
    std::vector<double> table_values{};  // table: >= 2 values
    std::vector<double> table_times{};   // table: [s], strictly increasing; empty: use table_dt
    double table_dt{0.0};                // table: [s] > 0 when table_times is empty

    [[nodiscard]] bool is_valid(double sample_time, std::string* why) const;
  };

  static constexpr std::size_t kStateSize = 6;

  // Throws ParameterError naming the parameter ("WaveGenerator.frequency: ...").
  WaveGenerator(Config config, double sample_time);

  [[nodiscard]] const Config& config() const noexcept { return config_; }
  // Current period in samples (P).
  [[nodiscard]] double period_samples() const noexcept { return period_samples_; }

  // w[k]; then advances one sample.
  double step() noexcept;
  [[nodiscard]] bool done() const noexcept { return done_; }
  // Periods played since the start (fractional).
  [[nodiscard]] double cycles() const noexcept;

  // New frequency [Hz] from the next sample, keeping the position in the period. False, and no
  // change, when frequency is out of range (<= 0, or >= 0.45 / Ts; staircase and table also take
  // 0 for the natural period).
  bool set_frequency(double frequency) noexcept;
  // Back to the start phase with nothing played, at the configured frequency.
  void restart() noexcept;

  [[nodiscard]] static constexpr std::size_t state_size() noexcept { return kStateSize; }
  void save_state(std::span<double> out) const noexcept;
  void restore_state(std::span<const double> in) noexcept;

 private:
  [[nodiscard]] bool samples_for(double frequency, double* samples) const noexcept;
  [[nodiscard]] double unit_shape(double p) const noexcept;
  [[nodiscard]] double table_at(double p) const noexcept;
  [[nodiscard]] double end_value() const noexcept;

  Config config_{};
  double ts_{0.0};
  double natural_period_{0.0};  // [s] staircase and table; 0 otherwise
  // State.
  double period_samples_{0.0};  // P
  double origin_{0.0};          // x at the last (re)start or frequency change [samples]
  std::uint64_t count_{0};      // samples since then
  double cycles_before_{0.0};   // periods played before then
  bool done_{false};
  double hold_{0.0};
};

}  // namespace selfsense::control
