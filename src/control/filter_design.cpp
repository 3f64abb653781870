#include "selfsense/control/filter_design.hpp"

#include <cmath>
#include <string_view>

#include "selfsense/control/parameter_error.hpp"

namespace selfsense::control {
namespace {

bool design_frequency(std::string_view name, double frequency, double sample_time,
                      std::string* why) {
  return check::positive("sample_time", sample_time, why) &&
         check::positive(name, frequency, why) &&
         check::below(name, frequency, kMaxDesignFraction / sample_time, "0.45 * sample rate", why);
}

double omega(double frequency) {
  return 2.0 * std::numbers::pi * frequency;
}

}  // namespace

BiquadCoefficients bilinear(const AnalogBiquad& analog, double sample_time,
                            double prewarp_frequency) {
  std::string why;
  require_valid(check::positive("sample_time", sample_time, &why), why);
  double k = 2.0 / sample_time;
  if (prewarp_frequency > 0.0) {
    require_valid(design_frequency("prewarp_frequency", prewarp_frequency, sample_time, &why), why);
    const double w = omega(prewarp_frequency);
    k = w / std::tan(0.5 * w * sample_time);
  }
  BiquadCoefficients c;
  if (analog.n2 == 0.0 && analog.d2 == 0.0) {
    // First order: multiply through by (1 + z^-1) only, or a pole lands on z = -1.
    const double a0 = analog.d1 * k + analog.d0;
    c.b0 = (analog.n1 * k + analog.n0) / a0;
    c.b1 = (analog.n0 - analog.n1 * k) / a0;
    c.a1 = (analog.d0 - analog.d1 * k) / a0;
  } else {
    // Second order: multiply through by (1 + z^-1)^2 and collect powers of z^-1.
    const double k2 = k * k;
    const double a0 = analog.d2 * k2 + analog.d1 * k + analog.d0;
    c.b0 = (analog.n2 * k2 + analog.n1 * k + analog.n0) / a0;
    c.b1 = 2.0 * (analog.n0 - analog.n2 * k2) / a0;
    c.b2 = (analog.n2 * k2 - analog.n1 * k + analog.n0) / a0;
    c.a1 = 2.0 * (analog.d0 - analog.d2 * k2) / a0;
    c.a2 = (analog.d2 * k2 - analog.d1 * k + analog.d0) / a0;
  }
  require_valid(c.is_valid(&why), why);
  return c;
}

bool NotchDesign::is_valid(double sample_time, std::string* why) const {
  if (!design_frequency("NotchDesign.frequency", frequency, sample_time, why)) return false;
  if (quality > 0.0) {
    if (!check::finite("NotchDesign.quality", quality, why)) return false;
  } else if (!check::non_negative("NotchDesign.quality", quality, why) ||
             !check::positive("NotchDesign.bandwidth", bandwidth, why)) {
    return false;
  }
  return check::non_negative("NotchDesign.depth_db", depth_db, why);
}

bool SecondOrderDesign::is_valid(double sample_time, std::string* why) const {
  return design_frequency("SecondOrderDesign.frequency", frequency, sample_time, why) &&
         check::positive("SecondOrderDesign.quality", quality, why);
}

bool FirstOrderDesign::is_valid(double sample_time, std::string* why) const {
  return design_frequency("FirstOrderDesign.frequency", frequency, sample_time, why);
}

BiquadCoefficients notch(const NotchDesign& design, double sample_time) {
  std::string why;
  require_valid(design.is_valid(sample_time, &why), why);
  const double w0 = omega(design.frequency);
  const double zeta = 0.5 / design.q();
  const double g = std::pow(10.0, -design.depth_db / 20.0);
  const AnalogBiquad analog{1.0, 2.0 * g * zeta * w0, w0 * w0, 1.0, 2.0 * zeta * w0, w0 * w0};
  return bilinear(analog, sample_time, design.frequency);
}

BiquadCoefficients low_pass(const SecondOrderDesign& design, double sample_time) {
  std::string why;
  require_valid(design.is_valid(sample_time, &why), why);
  const double w0 = omega(design.frequency);
  const AnalogBiquad analog{0.0, 0.0, w0 * w0, 1.0, w0 / design.quality, w0 * w0};
  return bilinear(analog, sample_time, design.frequency);
}

BiquadCoefficients high_pass(const SecondOrderDesign& design, double sample_time) {
  std::string why;
  require_valid(design.is_valid(sample_time, &why), why);
  const double w0 = omega(design.frequency);
  const AnalogBiquad analog{1.0, 0.0, 0.0, 1.0, w0 / design.quality, w0 * w0};
  return bilinear(analog, sample_time, design.frequency);
}

BiquadCoefficients low_pass(const FirstOrderDesign& design, double sample_time) {
  std::string why;
  require_valid(design.is_valid(sample_time, &why), why);
  const double w0 = omega(design.frequency);
  const AnalogBiquad analog{0.0, 0.0, w0, 0.0, 1.0, w0};
  return bilinear(analog, sample_time, design.frequency);
}

BiquadCoefficients high_pass(const FirstOrderDesign& design, double sample_time) {
  std::string why;
  require_valid(design.is_valid(sample_time, &why), why);
  const double w0 = omega(design.frequency);
  const AnalogBiquad analog{0.0, 1.0, 0.0, 0.0, 1.0, w0};
  return bilinear(analog, sample_time, design.frequency);
}

}  // namespace selfsense::control
