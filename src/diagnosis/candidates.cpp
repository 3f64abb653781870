#include "candidates.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string_view>

#include "text.hpp"

namespace selfsense::diagnosis::detail {
namespace {

std::vector<double> rate_of(std::span<const double> x, double ts) {
  std::vector<double> out(x.size(), 0.0);
  for (std::size_t k = 1; k < x.size(); ++k)
    out[k] = (x[k] - x[k - 1]) / ts;
  if (out.size() > 1) out[0] = out[1];
  return out;
}

void describe_offset(Finding& f, const Evidence& e) {
  const ChannelCorrection& c = e.c;
  const std::string& n = e.ch.name;
  const std::string& tail = e.tail;
  const double pct = e.pct;
  const std::vector<double>& before = e.before;
  f.evidence = "the recorded " + n +
               format(" is offset by %.3g %% of its range and scaled by %.4g", c.offset * pct,
                      1.0 + c.gain) +
               tail;
  f.feature_name = "model output";
  f.feature = before;
}

void describe_leakage(Finding& f, const Evidence& e) {
  const ChannelCorrection& c = e.c;
  const Signals& s = e.s;
  const std::string& n = e.ch.name;
  const std::string& tail = e.tail;
  const std::vector<double>& before = e.before;
  if (c.leakage_tau_s > 0.0) {
    f.evidence = "the measured " + n +
                 format(
                     " forgets its charge with a time constant of %.3g s (charge amplifier "
                     "feedback or insulation resistance)",
                     c.leakage_tau_s) +
                 tail;
  } else {
    // The stack's conductance passes a current sigma E that the charge amplifier collects too,
    // so the measured D gains sigma times the field's integral (lost where it is subtracted).
    f.evidence = "the measured " + n +
                 format(c.drive_integral_per_s >= 0.0
                            ? " gains charge in proportion to the integral of the field (a "
                              "parallel conductance of the stack: %.3g S/m)"
                            : " loses charge in proportion to the integral of the field (%.3g "
                              "S/m)",
                        std::abs(c.drive_integral_per_s)) +
                 tail;
  }
  f.feature_name = "time [s]";
  f.feature.resize(before.size());
  for (std::size_t k = 0; k < before.size(); ++k) {
    f.feature[k] = static_cast<double>(k) * s.sample_time;
  }
}

void describe_delay(Finding& f, const Evidence& e) {
  const ChannelCorrection& c = e.c;
  const Signals& s = e.s;
  const std::string& n = e.ch.name;
  const std::string& tail = e.tail;
  f.evidence = "the recorded " + n +
               format(" lags the model by %.3g samples (%.3g ms): channels sampled out of step",
                      c.delay_s / s.sample_time, c.delay_s * 1e3) +
               tail;
  f.feature_name = "rate of the drive [1/s]";
  f.feature = rate_of(s.drive, s.sample_time);
}

void describe_dynamics(Finding& f, const Evidence& e) {
  const ChannelCorrection& c = e.c;
  const Signals& s = e.s;
  const std::string& n = e.ch.name;
  const std::string& tail = e.tail;
  // Below its frequency the second-order low-pass is 1 - (2 zeta / w0) s + ((4 zeta^2 - 1) /
  // w0^2) s^2 + ..., a delay tau = 2 zeta / w0 is 1 - tau s + (tau^2 / 2) s^2 + ...: at zeta =
  // 1/sqrt(2) they agree to second order, and from there up the low-pass has no resonant peak.
  // Such a fit is a lag of the channel, as an acquisition chain's anti-aliasing filter and
  // sampling lag it (Butterworth 0.71, Bessel 0.87), not a mechanical mode: named a delay. Its
  // lag is the stage's filter's at DC (bilinear, prewarped at f0): zeta Ts / tan(w0 Ts / 2),
  // 2 zeta / w0 well below Nyquist.
  if (c.dynamics_damping >= kNoResonanceDamping && c.dynamics2_frequency_hz == 0.0) {
    const double omega = 2.0 * std::numbers::pi * c.dynamics_frequency_hz;
    const double lag_s = c.dynamics_damping * s.sample_time / std::tan(omega * s.sample_time / 2.0);
    f.effect = "delay";
    f.evidence = "the recorded " + n +
                 format(
                     " lags the model by %.3g samples (%.3g ms) and is smoothed above the "
                     "excitation's band, without resonance: channels sampled out of step ",
                     lag_s / s.sample_time, lag_s * 1e3) +
                 format("through a low-pass (second order, %.4g Hz, damping %.2g)",
                        c.dynamics_frequency_hz, c.dynamics_damping) +
                 tail;
  } else if (c.dynamics2_frequency_hz > 0.0) {
    const double first = 1.0 - c.dynamics_direct - c.dynamics2_share;
    f.evidence = "the recorded " + n +
                 format(
                     " rings and lags at fast changes like two resonances, at %.4g Hz with %.2g "
                     "damping (share %.2g)",
                     c.dynamics_frequency_hz, c.dynamics_damping, first) +
                 format(" and at %.4g Hz with %.2g damping (share %.2g)", c.dynamics2_frequency_hz,
                        c.dynamics2_damping, c.dynamics2_share) +
                 format(", %.2g of it passing neither (inertia of stack and load, two modes)",
                        c.dynamics_direct) +
                 tail;
  } else {
    f.evidence =
        "the recorded " + n +
        format(
            " rings and lags at fast changes like a resonance at %.4g Hz with %.2g "
            "damping (inertia of stack and load)",
            c.dynamics_frequency_hz, c.dynamics_damping) +
        (c.dynamics_direct != 0.0 ? format(", %.2g of it passing the mode by", c.dynamics_direct)
                                  : std::string()) +
        tail;
  }
  f.feature_name = "rate of the drive [1/s]";
  f.feature = rate_of(s.drive, s.sample_time);
}

void describe_creep(Finding& f, const Evidence& e) {
  const ChannelCorrection& c = e.c;
  const Signals& s = e.s;
  const std::string& n = e.ch.name;
  const std::string& tail = e.tail;
  const double range = e.range;
  // Lags of the response (per unit of it) or of the drive (per unit of the drive: scaled by
  // the channel's mean slope to the drive to read as a share of the step).
  const bool of_drive = c.creep_eigenvalues.empty();
  const std::vector<double>& lambda = of_drive ? c.drive_creep_eigenvalues : c.creep_eigenvalues;
  double total = 0.0;
  for (const double w : of_drive ? c.drive_creep_weights : c.creep_weights)
    total += w;
  if (of_drive) {
    const double drive_range = range_of(s.drive);
    total *= drive_range > 0.0 && range > 0.0 ? drive_range / range : 0.0;
  }
  const double decades =
      lambda.empty() ? 1.0 : std::max(1.0, std::log10(lambda.back() / lambda.front()));
  const std::string span =
      decades > 1.0 ? format("%.2g decades of lags", decades) : std::string("lags over a decade");
  f.evidence =
      "after steps of the drive the recorded " + n +
      format(" keeps moving by %.2g %% of the step per decade of time (", 100.0 * total / decades) +
      span + (of_drive ? ", driven by the input" : ", driven by the model's output") + ")" + tail;
  f.feature_name = "log10 time since the drive last stepped [s]";
  f.feature = log_time_since_step(s.drive, s.sample_time);
}

void describe_hysteresis(Finding& f, const Evidence& e) {
  const ChannelCorrection& c = e.c;
  const Signals& s = e.s;
  const std::string& n = e.ch.name;
  const std::string& tail = e.tail;
  const double pct = e.pct;
  // The loop the added plays draw: their term's spread over the recording.
  models::ChannelCorrection plays_only;
  plays_only.hysteresis_thresholds = c.hysteresis_thresholds;
  plays_only.hysteresis_weights = c.hysteresis_weights;
  plays_only.hinge_thresholds = c.hinge_thresholds;
  plays_only.hinge_levels = c.hinge_levels;
  plays_only.hinge_weights = c.hinge_weights;
  models::CorrectionStage stage(plays_only, s.sample_time);
  std::vector<double> term(s.drive.size());
  for (std::size_t k = 0; k < term.size(); ++k) {
    models::CorrectionStage::Inputs in;
    in.drive = s.drive[k];
    term[k] = stage.step(in);
  }
  const double spread = range_of(term);
  f.evidence = "the recorded " + n +
               (f.effect == "hysteresis"
                    ? format(" differs on rising and falling branches at the same drive beyond "
                             "the model (the added loop spans %.3g %% of range)",
                             spread * pct)
                    : format(" has loops whose shape changes with their offset and saturates "
                             "at one end beyond the model (the added term spans %.3g %% of "
                             "range)",
                             spread * pct)) +
               tail;
  f.feature_name = "drive";
  f.feature.assign(s.drive.begin(), s.drive.end());
}

void describe_temperature(Finding& f, const Evidence& e) {
  const ChannelCorrection& c = e.c;
  const Signals& s = e.s;
  const std::string& n = e.ch.name;
  const std::string& tail = e.tail;
  const double pct = e.pct;
  f.evidence = "the recorded " + n +
               format(
                   " follows the temperature: gain %.3g %%/K, offset %.3g %% of range/K "
                   "over %.3g K",
                   100.0 * c.temperature_gain_per_k, c.temperature_offset_per_k * pct,
                   range_of(s.temperature)) +
               (c.temperature_gain_per_k2 != 0.0 || c.temperature_offset_per_k2 != 0.0
                    ? format(" (and %.3g %%/K^2, %.3g %% of range/K^2: quadratic in the change)",
                             100.0 * c.temperature_gain_per_k2, c.temperature_offset_per_k2 * pct)
                    : std::string()) +
               tail;
  f.feature_name = "temperature [degC]";
  f.feature.assign(s.temperature.begin(), s.temperature.end());
}

void describe_stress(Finding& f, const Evidence& e) {
  const ChannelCorrection& c = e.c;
  const Signals& s = e.s;
  const std::string& n = e.ch.name;
  const std::string& tail = e.tail;
  const double pct = e.pct;
  if (c.stress_drive_per_pa != 0.0) {
    // Each part of the response with its own change per MPa, the drive's linear part (T x) at
    // the recording's RMS drive, the whole response's (T r) and, on the sensed channel, the
    // coupling's (T^2). On the strain, T x beside T r is the loop moving apart from the coupling.
    double x_rms = 0.0;
    for (const double x : s.drive)
      x_rms += x * x / static_cast<double>(s.drive.size());
    x_rms = std::sqrt(x_rms);
    f.evidence =
        "the recorded " + n +
        format(
            " follows the stress in each part of its response: the field's linear "
            "part changes by %.3g %% of range per MPa at the RMS field and the whole "
            "response by %.3g %% per MPa",
            c.stress_drive_per_pa * 1e6 * x_rms * pct, 100.0 * c.stress_gain_per_pa * 1e6) +
        (c.stress_quadratic_per_pa2 != 0.0
             ? format(", and the coupling bends with T^2 (%.3g %% of range at 1 MPa)",
                      c.stress_quadratic_per_pa2 * 1e12 * pct)
             : std::string(" (the loop moves apart from the coupling as the stress changes)")) +
        tail;
  } else if (c.stress_quadratic_per_pa2 != 0.0) {
    const double t = std::max(std::abs(*std::max_element(s.stress.begin(), s.stress.end())),
                              std::abs(*std::min_element(s.stress.begin(), s.stress.end())));
    f.evidence = "the recorded " + n +
                 format(
                     " bends with the square of the stress (the coupling changes with "
                     "stress; %.3g %% of range at %.3g MPa)",
                     std::abs(c.stress_quadratic_per_pa2) * t * t * pct, t * 1e-6) +
                 tail;
  } else {
    double mean = 0.0;
    for (const double t : s.stress)
      mean += t / static_cast<double>(s.stress.size());
    f.evidence = "the coupling of " + n +
                 format(
                     " changes with stress by %.3g %% per MPa over %.3g MPa, about the "
                     "recording's mean of %.3g MPa where the model's coupling was fitted",
                     100.0 * c.stress_gain_per_pa * 1e6, range_of(s.stress) * 1e-6, mean * 1e-6) +
                 tail;
  }
  f.feature_name = "stress T [Pa]";
  f.feature.assign(s.stress.begin(), s.stress.end());
}

void describe_permittivity(Finding& f, const Evidence& e) {
  const ChannelCorrection& c = e.c;
  const Signals& s = e.s;
  const std::string& n = e.ch.name;
  const std::string& tail = e.tail;
  const double pct = e.pct;
  const double x = std::max(std::abs(*std::max_element(s.drive.begin(), s.drive.end())),
                            std::abs(*std::min_element(s.drive.begin(), s.drive.end())));
  f.evidence =
      "the recorded " + n +
      format(
          " curves with the drive beyond the model (quadratic and cubic terms "
          "reach %.3g %% of range at the largest drive)",
          (std::abs(c.drive_quadratic) * x * x + std::abs(c.drive_cubic) * x * x * x) * pct) +
      tail;
  f.feature_name = "drive";
  f.feature.assign(s.drive.begin(), s.drive.end());
}

void describe_electrostriction(Finding& f, const Evidence& e) {
  const ChannelCorrection& c = e.c;
  const Signals& s = e.s;
  const std::string& n = e.ch.name;
  const std::string& tail = e.tail;
  const std::vector<double>& before = e.before;
  const ChannelData& ch = e.ch;
  if (c.sensed_quadratic != 0.0) {  // field drive: P ~ the model's D
    f.evidence = "the recorded " + n +
                 format(
                     " follows the square of the polarization (Q = %.3g m^4/C^2 on the "
                     "model's D - d T)",
                     c.sensed_quadratic) +
                 tail;
  } else {  // charge drive: P ~ the imposed D
    f.evidence = "the recorded " + n +
                 format(
                     " follows the square of the imposed polarization (butterfly: %.3g "
                     "D^2 %+.3g D^3)",
                     c.drive_quadratic, c.drive_cubic) +
                 tail;
  }
  f.feature_name = "polarization squared [(C/m^2)^2]";
  f.feature.resize(before.size());
  for (std::size_t k = 0; k < before.size(); ++k) {
    const double p = c.sensed_quadratic != 0.0 ? ch.sensed_model[k] : s.drive[k];
    f.feature[k] = p * p;
  }
}

}  // namespace

const std::vector<Candidate>& candidates() {
  static const std::vector<Candidate> list{
      {"offset", {CorrectionTerm::kOffset}, true, true, Needs::kNothing, &describe_offset},
      {"charge_leakage",
       {CorrectionTerm::kLeakage, CorrectionTerm::kOffset},
       true,
       false,
       Needs::kNothing,
       &describe_leakage},
      {"delay", {CorrectionTerm::kDelay}, true, true, Needs::kNothing, &describe_delay},
      {"dynamics", {CorrectionTerm::kDynamics}, false, true, Needs::kNothing, &describe_dynamics},
      // Two modes in parallel (a stack and its load, or a mount), and the share of the strain
      // that passes neither: the one-mode form's mode kept, the second searched beside it.
      {"dynamics",
       {CorrectionTerm::kDynamics, CorrectionTerm::kSecondMode},
       false,
       true,
       Needs::kNothing,
       &describe_dynamics,
       false,
       true},
      // On the sensed channel the lags follow its response to the drive alone (D - d T), which
      // the reconstruction knows before the measurement (affine models).
      {"creep",
       {CorrectionTerm::kCreep, CorrectionTerm::kOffset},
       true,
       true,
       Needs::kNothing,
       &describe_creep},
      // Creep driven by the input itself (the field's history, not the hysteresis output's).
      {"creep",
       {CorrectionTerm::kDriveCreep, CorrectionTerm::kOffset},
       true,
       true,
       Needs::kNothing,
       &describe_creep},
      // Charge lost through the stack's parallel conductance: in proportion to the integral of
      // the field (the high-pass above is the charge amplifier's feedback resistance).
      {"charge_leakage",
       {CorrectionTerm::kDriveIntegral, CorrectionTerm::kOffset},
       true,
       false,
       Needs::kNothing,
       &describe_leakage},
      {"hysteresis",
       {CorrectionTerm::kHysteresis, CorrectionTerm::kOffset},
       true,
       true,
       Needs::kNothing,
       &describe_hysteresis,
       true},
      {"asymmetric_hysteresis",
       {CorrectionTerm::kAsymmetricHysteresis, CorrectionTerm::kOffset},
       true,
       true,
       Needs::kNothing,
       &describe_hysteresis,
       true},
      {"temperature_dependence",
       {CorrectionTerm::kTemperature, CorrectionTerm::kOffset},
       true,
       true,
       Needs::kTemperature,
       &describe_temperature},
      // ... and quadratic in the temperature change (permittivity and coupling curve with it).
      {"temperature_dependence",
       {CorrectionTerm::kTemperature, CorrectionTerm::kTemperatureQuadratic,
        CorrectionTerm::kOffset},
       true,
       true,
       Needs::kTemperature,
       &describe_temperature},
      {"stress_dependence",
       {CorrectionTerm::kStress, CorrectionTerm::kOffset},
       false,
       true,
       Needs::kStress,
       &describe_stress},
      {"stress_dependence",
       {CorrectionTerm::kStressQuadratic, CorrectionTerm::kOffset},
       true,
       false,
       Needs::kStress,
       &describe_stress},
      // ... and on the sensed channel each part of the response apart: the permittivity (T x),
      // the loop with it (T r) and the coupling (T^2), all linear in T given the drive, so the
      // reconstruction solves them with the sensor coupling (models/channel_correction.hpp).
      {"stress_dependence",
       {CorrectionTerm::kStress, CorrectionTerm::kStressDrive, CorrectionTerm::kStressQuadratic,
        CorrectionTerm::kOffset},
       true,
       false,
       Needs::kStress,
       &describe_stress},
      // ... and on the strain the loop apart from the coupling: a loop that grows with stress
      // scales the hysteretic part of the response alone, T (r - a x), which T r and T x span.
      {"stress_dependence",
       {CorrectionTerm::kStress, CorrectionTerm::kStressDrive, CorrectionTerm::kOffset},
       false,
       true,
       Needs::kStress,
       &describe_stress},
      {"permittivity_nonlinearity",
       {CorrectionTerm::kDrivePolynomial},
       true,
       false,
       Needs::kNothing,
       &describe_permittivity},
      // S ~ P^2: the model's D for field drive, the imposed D (the drive) for charge drive.
      {"electrostriction",
       {CorrectionTerm::kSensedQuadratic, CorrectionTerm::kOffset},
       false,
       true,
       Needs::kSensed,
       &describe_electrostriction},
      {"electrostriction",
       {CorrectionTerm::kDrivePolynomial, CorrectionTerm::kOffset},
       false,
       true,
       Needs::kChargeDrive,
       &describe_electrostriction},
  };
  return list;
}

bool uses_term(const Candidate& c, CorrectionTerm t) {
  return std::find(c.terms.begin(), c.terms.end(), t) != c.terms.end();
}

bool applicable(const Candidate& c, const ChannelData& ch, const Signals& s, bool has_sensed,
                bool charge_drive) {
  if (ch.sensed ? !c.on_sensed : !c.on_strain) return false;
  const auto uses = [&](CorrectionTerm t) { return uses_term(c, t); };
  // The terms in T on the sensed channel are solved with the sensor coupling; leakage is a
  // charge's.
  if ((uses(CorrectionTerm::kStressQuadratic) || uses(CorrectionTerm::kStressDrive)) && ch.sensed &&
      ch.coupling == 0.0) {
    return false;
  }
  if ((uses(CorrectionTerm::kLeakage) || uses(CorrectionTerm::kDriveIntegral)) && charge_drive) {
    return false;
  }
  if (uses(CorrectionTerm::kCreep) && ch.sensed && !ch.affine) return false;
  if (c.generic && ch.loop_reidentified) return false;
  switch (c.needs) {
    case Needs::kTemperature:
      return range_of(s.temperature) > 1.0;
    case Needs::kStress:
      return range_of(s.stress) > 0.0;
    case Needs::kSensed:
      return has_sensed && !charge_drive;
    case Needs::kChargeDrive:
      return charge_drive;
    case Needs::kNothing:
      return true;
  }
  return true;
}

namespace {

// Creep keeps moving in the direction of the last step (eq. 28: lags with non-negative weights).
// The lags' response to a unit step of the model's response, s(t) = sum_j w_j (1 - exp(-l_j t)),
// must move with the step: never fall back past where it started, and give back at most half of
// what it gained (a ferroelectric relaxes partly after switching; a lag bank imitating charge
// leakage, or the phase of a periodic drive, gives it all back or turns against the step).
bool lags_move_with_the_step(const std::vector<double>& eigenvalues,
                             const std::vector<double>& weights) {
  const auto s = [&](double t) {
    double sum = 0.0;
    for (std::size_t j = 0; j < weights.size(); ++j)
      sum += weights[j] * -std::expm1(-eigenvalues[j] * t);
    return sum;
  };
  if (eigenvalues.empty()) return false;
  const auto [lo, hi] = std::minmax_element(eigenvalues.begin(), eigenvalues.end());
  // 20 points per decade from a tenth of the fastest time constant to 100 slowest ones.
  const double t0 = 0.1 / *hi;
  const auto points = static_cast<int>(std::ceil(20.0 * std::log10(1000.0 * *hi / *lo)));
  double peak = 0.0;
  double lowest = 0.0;
  for (int i = 0; i <= points; ++i) {
    const double v = s(t0 * std::pow(10.0, 0.05 * i));
    peak = std::max(peak, v);
    lowest = std::min(lowest, v);
  }
  const double final_value = s(std::numeric_limits<double>::infinity());
  return peak > 0.0 && lowest >= -0.05 * peak && final_value >= 0.5 * peak;
}

}  // namespace

// Both forms of creep (lags of the response, lags of the drive): each bank present moves with
// the step (the drive raises D and S, so the drive's lags must push the same way; a channel of
// inverted polarity would need the slope's sign first, which no channel here has).
bool creep_moves_with_the_step(const ChannelCorrection& c) {
  if (c.creep_eigenvalues.empty() && c.drive_creep_eigenvalues.empty()) return false;
  return (c.creep_eigenvalues.empty() ||
          lags_move_with_the_step(c.creep_eigenvalues, c.creep_weights)) &&
         (c.drive_creep_eigenvalues.empty() ||
          lags_move_with_the_step(c.drive_creep_eigenvalues, c.drive_creep_weights));
}

bool extensible(const ChannelCorrection& simpler_fit) {
  return simpler_fit.dynamics_damping < kNoResonanceDamping;
}

bool named_already(const std::vector<const Candidate*>& used, const Candidate& c) {
  return std::any_of(used.begin(), used.end(), [&](const Candidate* u) {
    return std::string_view(u->effect) == std::string_view(c.effect);
  });
}

bool is_creep(const Candidate& c) {
  return uses_term(c, CorrectionTerm::kCreep) || uses_term(c, CorrectionTerm::kDriveCreep);
}

bool searches_filter(const Candidate& c, const ChannelCorrection& accepted) {
  for (const CorrectionTerm t : c.terms) {
    if ((t == CorrectionTerm::kLeakage && accepted.leakage_tau_s == 0.0) ||
        (t == CorrectionTerm::kDelay && accepted.delay_s == 0.0) ||
        (t == CorrectionTerm::kDynamics && accepted.dynamics_frequency_hz == 0.0) ||
        (t == CorrectionTerm::kSecondMode && accepted.dynamics2_frequency_hz == 0.0)) {
      return true;
    }
  }
  return false;
}

std::size_t complexity(const std::vector<CorrectionTerm>& terms) {
  const auto uses = [&](CorrectionTerm t) {
    return std::find(terms.begin(), terms.end(), t) != terms.end();
  };
  std::size_t n = 0;
  for (const CorrectionTerm t : terms) {
    switch (t) {
      case CorrectionTerm::kOffset:
      case CorrectionTerm::kDrivePolynomial:
      case CorrectionTerm::kStressDrive:
      case CorrectionTerm::kDynamics:
        n += 2;
        break;
      case CorrectionTerm::kTemperature:  // gain, offset, drive, stress (each per K or K^2)
      case CorrectionTerm::kTemperatureQuadratic:
      case CorrectionTerm::kSecondMode:  // f2, zeta2 and the two shares
        n += 4;
        break;
      case CorrectionTerm::kCreep:
      case CorrectionTerm::kDriveCreep:
        n += 5;
        break;
      case CorrectionTerm::kStress:  // T r, and T unless kStressDrive brings it
        n += uses(CorrectionTerm::kStressDrive) ? 1U : 2U;
        break;
      case CorrectionTerm::kHysteresis:
        n += 9;  // the linear play and 8 plays (correction_fit.cpp)
        break;
      case CorrectionTerm::kAsymmetricHysteresis:
        n += 9 + 27;  // plays and their hinges
        break;
      default:
        n += 1;
        break;
    }
  }
  return n;
}

std::vector<CorrectionTerm> merged(const std::vector<CorrectionTerm>& a,
                                   const std::vector<CorrectionTerm>& b) {
  std::vector<CorrectionTerm> out = a;
  for (const CorrectionTerm t : b) {
    if (std::find(out.begin(), out.end(), t) == out.end()) out.push_back(t);
  }
  return out;
}

std::vector<double> log_time_since_step(std::span<const double> x, double ts) {
  std::vector<double> out(x.size());
  const double step = 0.05 * range_of(x);
  double anchor = x.empty() ? 0.0 : x[0];
  std::size_t since = 0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    if (std::abs(x[k] - anchor) > step) {
      anchor = x[k];
      since = k;
    }
    out[k] = std::log10(static_cast<double>(k - since + 1) * ts);
  }
  return out;
}

void describe(Finding& f, const Candidate& candidate, const ChannelCorrection& c,
              const ChannelData& ch, const Signals& s, const std::vector<double>& before,
              const std::vector<double>& after, const std::string& judged) {
  const double range = range_of(ch.recorded);
  const double pct = range > 0.0 ? 100.0 / range : 0.0;
  double largest = 0.0;
  for (std::size_t k = 0; k < before.size(); ++k) {
    largest = std::max(largest, std::abs(after[k] - before[k]));
  }
  const Evidence e{
      c,
      ch,
      s,
      before,
      range,
      pct,
      format("; modelled, it removes %.0f %% of the residual variance ", 100.0 * f.explains) +
          judged + format(" (largest change %.2g %% of range)", largest * pct)};
  candidate.describe(f, e);
}

}  // namespace selfsense::diagnosis::detail
