#include "selfsense/control/damping_controller.hpp"

#include <cassert>
#include <cmath>
#include <numbers>

#include "selfsense/base/format_number.hpp"
#include "selfsense/control/filter_design.hpp"
#include "selfsense/control/parameter_error.hpp"

namespace selfsense::control {

bool DampingController::Params::is_valid(double sample_time, std::string* why) const {
  if (!check::positive("DampingController.sample_time", sample_time, why) ||
      !check::positive("DampingController.gain", gain, why) ||
      !check::positive("DampingController.frequency", frequency, why) ||
      !check::below("DampingController.frequency", frequency, kMaxDesignFraction / sample_time,
                    "0.45 * sample rate", why)) {
    return false;
  }
  if (std::isnan(output_limit) || !(output_limit > 0.0)) {
    return check::fail("DampingController.output_limit",
                       base::format_number(output_limit) + " must be > 0", why);
  }
  if (!check::non_negative("DampingController.dc_block_frequency", dc_block_frequency, why) ||
      (dc_block_frequency > 0.0 &&
       !check::below("DampingController.dc_block_frequency", dc_block_frequency,
                     kMaxDesignFraction / sample_time, "0.45 * sample rate", why))) {
    return false;
  }
  return law != Law::kPositivePosition ||
         check::positive("DampingController.damping", damping, why);
}

DampingController::DampingController(const Params& params, double sample_time) : params_(params) {
  std::string why;
  require_valid(params_.is_valid(sample_time, &why), why);
  if (params_.law == Law::kPositivePosition) {
    filter_ =
        Biquad(low_pass(SecondOrderDesign{params_.frequency, 0.5 / params_.damping}, sample_time));
    signed_gain_ = params_.gain;
  } else {
    const double tau = 1.0 / (2.0 * std::numbers::pi * params_.frequency);
    // No pre-warping: K = 2 / Ts keeps the derivative exact at low frequency.
    filter_ = Biquad(bilinear(AnalogBiquad{0.0, 1.0, 0.0, 0.0, tau, 1.0}, sample_time, 0.0));
    signed_gain_ = -params_.gain;
  }
  if (params_.dc_block_frequency > 0.0) {
    dc_block_ = Biquad(high_pass(FirstOrderDesign{params_.dc_block_frequency}, sample_time));
  }
}

void DampingController::reset(double measurement) noexcept {
  dc_block_.reset(measurement);
  filter_.reset(dc_block_.coefficients().dc_gain() * measurement);
}

void DampingController::save_state(std::span<double> out) const noexcept {
  assert(out.size() >= kStateSize);
  dc_block_.save_state(out.first(Biquad::kStateSize));
  filter_.save_state(out.subspan(Biquad::kStateSize, Biquad::kStateSize));
}

void DampingController::restore_state(std::span<const double> in) noexcept {
  assert(in.size() >= kStateSize);
  dc_block_.restore_state(in.first(Biquad::kStateSize));
  filter_.restore_state(in.subspan(Biquad::kStateSize, Biquad::kStateSize));
}

}  // namespace selfsense::control
