// What `selfsense demo` shows of the hysteresis-creep operator of a typical stack
// (operators/typical_stack.hpp): what a piezo user looks at first (stroke, loop width, creep per
// decade) and what the inverse compensator makes of the hysteresis. All strains [-].
#pragma once

#include <cstddef>
#include <vector>

namespace selfsense::evaluation {

struct StackDemoSettings {
  double sample_rate{1000.0};  // [Hz]
  double sine_hz{1.0};
  int cycles{3};
  int steps{5};
  double hold_s{20.0};  // each stair's hold
};

struct StackDemoFigures {
  // A sine between 0 and full field: the last cycle's stroke and loop width (the largest
  // difference between the falling and the rising branch at equal field).
  double stroke{0.0};
  double loop_width{0.0};
  // A staircase of `steps` equal field steps with holds: each step's jump (from the end of the
  // previous hold to the end of its own) and its creep from 0.1 s to the end of the hold.
  struct Step {
    double field{0.0};  // [V/m]
    double jump{0.0};
    double creep{0.0};
  };
  std::vector<Step> stairs{};
  double decades{0.0};  // of the hold after its first 0.1 s
  // A sine of strain between 10 % and 90 % of the stroke, followed with a straight line through
  // the origin and with the inverse compensator (model = plant): the largest errors.
  double error_linear{0.0};
  double error_compensated{0.0};
  std::size_t limited{0};  // compensator samples limited to 0 .. full field
};

[[nodiscard]] StackDemoFigures stack_demo(const StackDemoSettings& settings);

}  // namespace selfsense::evaluation
