// `selfsense demo`: drives the hysteresis-creep operator of a typical stack with a sine and a
// staircase and prints what a piezo user looks at first: stroke, loop width, creep per
// decade, and what the inverse compensator makes of the hysteresis (evaluation/stack_demo.hpp).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>

#include "commands.hpp"
#include "selfsense/evaluation/stack_demo.hpp"
#include "selfsense/operators/typical_stack.hpp"

namespace selfsense::cli {
namespace {

using operators::kTypicalFieldMax;

constexpr double kStackLength = 10e-3;  // m, to print displacement in um
constexpr double kMicro = 1e6;

double um(double strain) {
  return strain * kStackLength * kMicro;
}

void run_demo(const evaluation::StackDemoSettings& opt) {
  const evaluation::StackDemoFigures f = evaluation::stack_demo(opt);
  std::printf("selfsense demo: hysteresis-creep operator of a typical 10 mm stack, Ts = %g ms\n\n",
              1e3 / opt.sample_rate);
  std::printf("sine 0 .. %.1f MV/m at %g Hz, %d cycles (last cycle):\n", kTypicalFieldMax * 1e-6,
              opt.sine_hz, opt.cycles);
  std::printf("  stroke       %6.2f um\n", um(f.stroke));
  std::printf("  loop width   %6.2f um = %4.1f %% of stroke\n\n", um(f.loop_width),
              100.0 * f.loop_width / f.stroke);
  std::printf("staircase %d x %.2f MV/m, %g s holds:\n", opt.steps,
              kTypicalFieldMax / opt.steps * 1e-6, opt.hold_s);
  std::printf("  step  jump [um]  creep 0.1 s -> %g s [um]  creep per decade [%% of jump]\n",
              opt.hold_s);
  for (std::size_t i = 0; i < f.stairs.size(); ++i) {
    const auto& step = f.stairs[i];
    std::printf("  %4zu  %9.3f  %24.3f  %27.2f\n", i + 1, um(step.jump), um(step.creep),
                100.0 * step.creep / f.decades / step.jump);
  }
  const double range = 0.8 * f.stroke;
  std::printf("\nfeedforward on a %g Hz sine of %.1f um (max error over %d cycles):\n", opt.sine_hz,
              um(range), opt.cycles);
  std::printf("  linear gain only      %8.4f um = %6.2f %% of range\n", um(f.error_linear),
              100.0 * f.error_linear / range);
  std::printf(
      "  inverse compensator   %8.2e um = %6.2e %% of range (model = plant here; %zu samples "
      "limited to 0 .. %.0f MV/m)\n",
      um(f.error_compensated), 100.0 * f.error_compensated / range, f.limited,
      kTypicalFieldMax * 1e-6);
}

}  // namespace

void add_demo_command(CLI::App& app) {
  auto options = std::make_shared<evaluation::StackDemoSettings>();
  CLI::App* cmd = app.add_subcommand(
      "demo", "Drive the hysteresis-creep operator of a typical stack and print a summary");
  cmd->add_option("--rate", options->sample_rate, "Sample rate [Hz]")->check(CLI::Range(10.0, 1e6));
  cmd->add_option("--hold", options->hold_s, "Hold time of each stair [s]")
      ->check(CLI::Range(0.2, 3600.0));
  cmd->callback([options] { run_demo(*options); });
}

}  // namespace selfsense::cli
