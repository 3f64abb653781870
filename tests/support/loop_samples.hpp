// A loop sample that looks like a running loop at 20 kHz (a 3 Hz sine through E, D, the
// estimates and the setpoint), for the recorder's tests and its benchmark.
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>

#include "selfsense/runtime/loop_sample.hpp"

namespace selfsense::test {

inline constexpr double kSampleTime = 5e-5;  // 20 kHz

inline runtime::LoopSample synthetic_sample(std::int64_t cycle) {
  const double t = static_cast<double>(cycle) * kSampleTime;
  const double phase = 2.0 * std::numbers::pi * 3.0 * t;
  runtime::LoopSample s;
  s.cycle = cycle;
  s.t = t;
  s.e = 1.0e6 * (1.0 + std::sin(phase));
  s.d = 0.02 * (1.0 + std::sin(phase - 0.1));
  s.t_hat = -1.0e5 * std::cos(phase);
  s.s_hat = 5e-4 * (1.0 + std::sin(phase - 0.05));
  s.setpoint = 5e-4 * (1.0 + std::sin(phase));
  s.command = s.e;
  s.s_ref = s.s_hat * 1.001;
  s.t_ref = s.t_hat * 0.999;
  s.state = runtime::LoopState::kArmed;
  s.driver_status = static_cast<std::uint16_t>(cycle % 3);
  return s;
}

}  // namespace selfsense::test
