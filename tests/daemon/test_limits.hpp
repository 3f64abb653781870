// The request limits the daemon tests use: a stack with a 1.5e-3 strain stroke and up to
// 20 MPa of compressive stress, a 10 kHz loop.
#pragma once

#include "selfsense/daemon/control_protocol.hpp"

namespace selfsense::daemon::test {

inline RequestLimits limits(runtime::ControlMode mode = runtime::ControlMode::kPosition) {
  RequestLimits out;
  out.mode = mode;
  out.setpoint[static_cast<std::size_t>(runtime::ControlMode::kPosition)] =
      SetpointRange{-1e-4, 1.5e-3};
  out.setpoint[static_cast<std::size_t>(runtime::ControlMode::kForce)] = SetpointRange{-2e7, 0.0};
  out.setpoint[static_cast<std::size_t>(runtime::ControlMode::kOpenLoop)] =
      SetpointRange{0.0, 1.5e-3};
  out.sample_time = 1e-4;
  out.max_frequency_hz = 1000.0;
  return out;
}

}  // namespace selfsense::daemon::test
