// Voltage amplifier driving the stack (AmplifierConfig in config.hpp):
//   du_max = Ts * min(slew_rate, current_limit / C_est)
//   u[k] = clamp(u[k-1] + clamp(u_cmd - u[k-1], -du_max, du_max), voltage_min, voltage_max)
// With the fault line asserted the output stage discharges the stack towards 0 V within the
// same limits. Disabled: ideal (u = u_cmd, 0 V under fault). update() is real-time safe.
#pragma once

#include <cstdint>

#include "selfsense/plant/config.hpp"

namespace selfsense::plant {

class Amplifier final {
 public:
  Amplifier() = default;
  Amplifier(const AmplifierConfig& config, double sample_time_s)
      : config_{config}, ts_{sample_time_s} {}
  void reset(double u) noexcept { u_ = u; }
  // Returns u (V); ORs StatusFlag bits for clipping, slew and current limit into *flags.
  double update(double u_cmd, double capacitance_f, bool fault, std::uint32_t* flags) noexcept;
  [[nodiscard]] double voltage() const noexcept { return u_; }

 private:
  AmplifierConfig config_{};
  double ts_{0.0};
  double u_{0.0};
};

}  // namespace selfsense::plant
