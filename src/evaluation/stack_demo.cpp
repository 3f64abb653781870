#include "selfsense/evaluation/stack_demo.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "selfsense/operators/hysteresis_creep.hpp"
#include "selfsense/operators/typical_stack.hpp"

namespace selfsense::evaluation {
namespace {

using operators::HysteresisCreep;
using operators::kTypicalFieldMax;

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

}  // namespace

StackDemoFigures stack_demo(const StackDemoSettings& settings) {
  StackDemoFigures out;
  const double ts = 1.0 / settings.sample_rate;
  const HysteresisCreep::Params params = operators::typical_stack_strain();

  // 1. Sine between 0 and full field.
  HysteresisCreep stack(params, ts);
  const auto per_cycle =
      static_cast<std::size_t>(std::lround(settings.sample_rate / settings.sine_hz));
  const std::size_t n = per_cycle * static_cast<std::size_t>(settings.cycles);
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
  out.stroke = stroke;
  out.loop_width = loop_width(e, s, last);

  // 2. Staircase with holds: creep after each step.
  HysteresisCreep stair(params, ts);
  const double step_field = kTypicalFieldMax / settings.steps;
  const auto hold = static_cast<std::size_t>(std::lround(settings.hold_s * settings.sample_rate));
  out.decades = std::log10(settings.hold_s / 0.1);
  double before = 0.0;
  for (int i = 1; i <= settings.steps; ++i) {
    const double field = step_field * i;
    double at_01 = 0.0;
    double at_end = 0.0;
    for (std::size_t k = 0; k < hold; ++k) {
      const double y = stair.step(field);
      if (k + 1 == static_cast<std::size_t>(std::lround(0.1 * settings.sample_rate))) at_01 = y;
      at_end = y;
    }
    out.stairs.push_back({field, at_end - before, at_end - at_01});
    before = at_end;
  }

  // 3. Inverse compensation of a sine of strain between 10 % and 90 % of the stroke (the lower
  // branch at 0 would need a negative field, which the amplifier range excludes).
  HysteresisCreep plant(params, ts);
  operators::HysteresisCreepCompensator feedforward(HysteresisCreep(params, ts), 0.0,
                                                    kTypicalFieldMax);
  const double gain = stroke / kTypicalFieldMax;  // best straight line through the origin
  HysteresisCreep open_loop(params, ts);
  for (std::size_t k = 0; k < n; ++k) {
    const double desired =
        stroke * (0.1 + 0.4 * (1.0 - std::cos(2.0 * std::numbers::pi * static_cast<double>(k) /
                                              static_cast<double>(per_cycle))));
    out.error_linear =
        std::max(out.error_linear, std::abs(open_loop.step(desired / gain) - desired));
    out.error_compensated =
        std::max(out.error_compensated, std::abs(plant.step(feedforward.step(desired)) - desired));
  }
  out.limited = feedforward.saturation_count();
  return out;
}

}  // namespace selfsense::evaluation
