#include "selfsense/plant/amplifier.hpp"

#include <algorithm>

#include "selfsense/plant/status.hpp"

namespace selfsense::plant {

double Amplifier::update(double u_cmd, double capacitance_f, bool fault,
                         std::uint32_t* flags) noexcept {
  const double target = fault ? 0.0 : u_cmd;
  if (!config_.enabled) {
    u_ = target;
    return u_;
  }
  const double slew_step = config_.slew_rate_v_per_s * ts_;
  const double current_step = config_.current_limit_a * ts_ / capacitance_f;
  const double du_max = std::min(slew_step, current_step);
  const double wanted = target - u_;
  double du = std::clamp(wanted, -du_max, du_max);
  if (du != wanted) *flags |= (current_step < slew_step) ? kCurrentLimited : kSlewLimited;
  double u = u_ + du;
  if (u > config_.voltage_max_v || u < config_.voltage_min_v) {
    u = std::clamp(u, config_.voltage_min_v, config_.voltage_max_v);
    *flags |= kVoltageClipped;
  }
  u_ = u;
  return u_;
}

}  // namespace selfsense::plant
