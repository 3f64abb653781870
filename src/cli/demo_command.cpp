// `selfsense demo`: drives the hysteresis-creep operator of a typical stack with a sine and a
// staircase and prints what a piezo user looks at first: stroke, loop width, creep per
// decade, and what the inverse compensator makes of the hysteresis.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "commands.hpp"
#include "selfsense/operators/hysteresis_creep.hpp"
#include "selfsense/operators/typical_stack.hpp"

namespace selfsense::cli {
namespace {

using operators::HysteresisCreep;
using operators::HysteresisCreepCompensator;
using operators::kTypicalFieldMax;

constexpr double kStackLength = 10e-3;  // m, to print displacement in um
constexpr double kMicro = 1e6;

struct DemoOptions {
  double sample_rate{1000.0};
  double sine_hz{1.0};
  int cycles{3};
  int steps{5};
  double hold_s{20.0};
};

// Loop width: the largest difference between the falling and the rising branch of the last
// cycle at equal field, found on a grid of field values.
double loop_width(const std::vector<double>& e, const std::vector<double>& s,
                  std::size_t cycle_start) {
  const std::size_t n = e.size() - cycle_start;
  const std::size_t half = n / 2;
  double width = 0.0;
  for (std::size_t k = cycle_start; k < cycle_start + half; ++k) {
    // Mirror sample on the falling half with the closest field.
    std::size_t best = cycle_start + half;
    for (std::size_t m = cycle_start + half; m < e.size(); ++m) {
      if (std::abs(e[m] - e[k]) < std::abs(e[best] - e[k])) best = m;
    }
    width = std::max(width, s[best] - s[k]);
  }
  return width;
}

void run_demo(const DemoOptions& opt) {
  const double ts = 1.0 / opt.sample_rate;
  const HysteresisCreep::Params params = operators::typical_stack_strain();
  std::printf("selfsense demo: hysteresis-creep operator of a typical 10 mm stack, Ts = %g ms\n\n",
              ts * 1e3);

  // 1. Sine between 0 and full field.
  HysteresisCreep stack(params, ts);
  const auto per_cycle = static_cast<std::size_t>(std::lround(opt.sample_rate / opt.sine_hz));
  const std::size_t n = per_cycle * static_cast<std::size_t>(opt.cycles);
  std::vector<double> e(n);
  std::vector<double> s(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double phase =
        2.0 * std::numbers::pi * static_cast<double>(k) / static_cast<double>(per_cycle);
    e[k] = 0.5 * kTypicalFieldMax * (1.0 - std::cos(phase));
  }
  stack.apply(e, s);
  const std::size_t last = n - per_cycle;
  const double s_min = *std::min_element(s.begin() + static_cast<std::ptrdiff_t>(last), s.end());
  const double s_max = *std::max_element(s.begin() + static_cast<std::ptrdiff_t>(last), s.end());
  const double stroke = s_max - s_min;
  const double width = loop_width(e, s, last);
  std::printf("sine 0 .. %.1f MV/m at %g Hz, %d cycles (last cycle):\n", kTypicalFieldMax * 1e-6,
              opt.sine_hz, opt.cycles);
  std::printf("  stroke       %6.2f um\n", stroke * kStackLength * kMicro);
  std::printf("  loop width   %6.2f um = %4.1f %% of stroke\n\n", width * kStackLength * kMicro,
              100.0 * width / stroke);

  // 2. Staircase with holds: creep after each step.
  HysteresisCreep stair(params, ts);
  const double step_field = kTypicalFieldMax / opt.steps;
  const auto hold = static_cast<std::size_t>(std::lround(opt.hold_s * opt.sample_rate));
  std::printf("staircase %d x %.2f MV/m, %g s holds:\n", opt.steps, step_field * 1e-6, opt.hold_s);
  std::printf("  step  jump [um]  creep 0.1 s -> %g s [um]  creep per decade [%% of jump]\n",
              opt.hold_s);
  double before = 0.0;
  for (int i = 1; i <= opt.steps; ++i) {
    const double field = step_field * i;
    double at_01 = 0.0;
    double at_end = 0.0;
    for (std::size_t k = 0; k < hold; ++k) {
      const double out = stair.step(field);
      if (k + 1 == static_cast<std::size_t>(std::lround(0.1 * opt.sample_rate))) at_01 = out;
      at_end = out;
    }
    const double jump = at_end - before;
    const double decades = std::log10(opt.hold_s / 0.1);
    std::printf("  %4d  %9.3f  %24.3f  %27.2f\n", i, jump * kStackLength * kMicro,
                (at_end - at_01) * kStackLength * kMicro,
                100.0 * (at_end - at_01) / decades / jump);
    before = at_end;
  }

  // 3. Inverse compensation of a sine of strain between 10 % and 90 % of the stroke (the lower
  // branch at 0 would need a negative field, which the amplifier range excludes).
  HysteresisCreep plant(params, ts);
  HysteresisCreepCompensator feedforward(HysteresisCreep(params, ts), 0.0, kTypicalFieldMax);
  const double gain = stroke / kTypicalFieldMax;  // best straight line through the origin
  double err_open = 0.0;
  double err_comp = 0.0;
  HysteresisCreep open_loop(params, ts);
  for (std::size_t k = 0; k < n; ++k) {
    const double desired =
        stroke * (0.1 + 0.4 * (1.0 - std::cos(2.0 * std::numbers::pi * static_cast<double>(k) /
                                              static_cast<double>(per_cycle))));
    err_open = std::max(err_open, std::abs(open_loop.step(desired / gain) - desired));
    err_comp = std::max(err_comp, std::abs(plant.step(feedforward.step(desired)) - desired));
  }
  std::printf("\nfeedforward on a %g Hz sine of %.1f um (max error over %d cycles):\n", opt.sine_hz,
              0.8 * stroke * kStackLength * kMicro, opt.cycles);
  std::printf("  linear gain only      %8.4f um = %6.2f %% of range\n",
              err_open * kStackLength * kMicro, 100.0 * err_open / (0.8 * stroke));
  std::printf(
      "  inverse compensator   %8.2e um = %6.2e %% of range (model = plant here; %zu samples "
      "limited to 0 .. %.0f MV/m)\n",
      err_comp * kStackLength * kMicro, 100.0 * err_comp / (0.8 * stroke),
      feedforward.saturation_count(), kTypicalFieldMax * 1e-6);
}

}  // namespace

void add_demo_command(CLI::App& app) {
  auto options = std::make_shared<DemoOptions>();
  CLI::App* cmd = app.add_subcommand(
      "demo", "Drive the hysteresis-creep operator of a typical stack and print a summary");
  cmd->add_option("--rate", options->sample_rate, "Sample rate [Hz]")->check(CLI::Range(10.0, 1e6));
  cmd->add_option("--hold", options->hold_s, "Hold time of each stair [s]")
      ->check(CLI::Range(0.2, 3600.0));
  cmd->callback([options] { run_demo(*options); });
}

}  // namespace selfsense::cli
