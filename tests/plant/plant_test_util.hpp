// Helpers shared by the plant tests: run a plant over a field sequence, measure loops.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include "selfsense/plant/plant.hpp"

namespace selfsense::plant::test {

inline std::vector<StepOutput> run_field(const PlantConfig& config, const std::vector<double>& e,
                                         double force_n = 0.0, double temp_degc = 25.0) {
  std::vector<StepInput> in(e.size());
  for (std::size_t i = 0; i < e.size(); ++i)
    in[i] = StepInput{e[i], force_n, temp_degc};
  return simulate(config, in);
}

// `cycles` periods of 0 .. 2 amplitude (offset + amplitude * -cos), starting at 0.
inline std::vector<double> cosine_cycles(double fs, double frequency_hz, int cycles,
                                         double amplitude = 1.0e6) {
  const auto n = static_cast<std::size_t>(std::llround(cycles * fs / frequency_hz));
  std::vector<double> e(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) / fs;
    e[k] = amplitude * (1.0 - std::cos(2.0 * std::numbers::pi * frequency_hz * t));
  }
  return e;
}

inline std::vector<double> step_field(std::size_t before, std::size_t after, double level) {
  std::vector<double> e(before + after, 0.0);
  std::fill(e.begin() + static_cast<std::ptrdiff_t>(before), e.end(), level);
  return e;
}

// Loop height of y over x at x = x_mid: falling-branch mean minus rising-branch mean, over the
// samples [from, to).
template <typename GetX, typename GetY>
double loop_height(const std::vector<StepOutput>& out, std::size_t from, std::size_t to,
                   double x_mid, double tolerance, GetX get_x, GetY get_y) {
  double up = 0.0;
  double down = 0.0;
  int n_up = 0;
  int n_down = 0;
  for (std::size_t k = from; k + 1 < to; ++k) {
    const double x = get_x(out[k]);
    if (std::abs(x - x_mid) > tolerance) continue;
    if (get_x(out[k + 1]) > x) {
      up += get_y(out[k]);
      ++n_up;
    } else {
      down += get_y(out[k]);
      ++n_down;
    }
  }
  if (n_up == 0 || n_down == 0) return 0.0;
  return down / n_down - up / n_up;
}

// Electrical energy taken in per unit volume (J/m^3) along samples first .. last: the trapezoidal
// integral of E dD. Over a closed cycle (E[last] = E[first], E symmetric in time) a single-valued
// D(E) gives 0 to rounding and a dissipative loop a positive area.
inline double loop_energy(const std::vector<StepOutput>& out, std::size_t first, std::size_t last) {
  double w = 0.0;
  for (std::size_t k = first; k < last; ++k) {
    w += 0.5 * (out[k].e_v_per_m + out[k + 1].e_v_per_m) *
         (out[k + 1].d_c_per_m2 - out[k].d_c_per_m2);
  }
  return w;
}

inline std::filesystem::path config_dir() {
  return std::filesystem::path{SELFSENSE_SOURCE_DIR} / "config" / "plant";
}

}  // namespace selfsense::plant::test
