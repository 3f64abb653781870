#include "selfsense/diagnosis/diagnosis.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include "selfsense/diagnosis/statistics.hpp"
#include "selfsense/identification/correction_fit.hpp"
#include "selfsense/models/runtime_model.hpp"

namespace selfsense::diagnosis {
namespace {

using identification::CorrectionTerm;
using models::ChannelCorrection;

enum class Needs : std::uint8_t { kNothing, kTemperature, kStress, kSensed, kChargeDrive };

// The effects of physics.md a channel correction can add, and the terms that model each.
struct Candidate {
  const char* effect;
  std::vector<CorrectionTerm> terms;
  bool on_sensed;  // the reconstruction can invert it on the sensed channel
  bool on_strain;
  Needs needs;
  // The hysteresis operators bend to many residuals (a static curve, a slow drift under a
  // periodic drive): chosen only when no specific physics explains the residual significantly.
  bool generic{false};
};

const std::vector<Candidate>& candidates() {
  static const std::vector<Candidate> list{
      {"offset", {CorrectionTerm::kOffset}, true, true, Needs::kNothing},
      {"charge_leakage",
       {CorrectionTerm::kLeakage, CorrectionTerm::kOffset},
       true,
       false,
       Needs::kNothing},
      {"delay", {CorrectionTerm::kDelay}, true, true, Needs::kNothing},
      {"dynamics", {CorrectionTerm::kDynamics}, false, true, Needs::kNothing},
      // On the sensed channel the lags follow its response to the drive alone (D - d T), which
      // the reconstruction knows before the measurement (affine models).
      {"creep", {CorrectionTerm::kCreep, CorrectionTerm::kOffset}, true, true, Needs::kNothing},
      // Creep driven by the input itself (the field's history, not the hysteresis output's).
      {"creep",
       {CorrectionTerm::kDriveCreep, CorrectionTerm::kOffset},
       true,
       true,
       Needs::kNothing},
      // Charge lost through the stack's parallel conductance: in proportion to the integral of
      // the field (the high-pass above is the charge amplifier's feedback resistance).
      {"charge_leakage",
       {CorrectionTerm::kDriveIntegral, CorrectionTerm::kOffset},
       true,
       false,
       Needs::kNothing},
      {"hysteresis",
       {CorrectionTerm::kHysteresis, CorrectionTerm::kOffset},
       true,
       true,
       Needs::kNothing,
       true},
      {"asymmetric_hysteresis",
       {CorrectionTerm::kAsymmetricHysteresis, CorrectionTerm::kOffset},
       true,
       true,
       Needs::kNothing,
       true},
      {"temperature_dependence",
       {CorrectionTerm::kTemperature, CorrectionTerm::kOffset},
       true,
       true,
       Needs::kTemperature},
      // ... and quadratic in the temperature change (permittivity and coupling curve with it).
      {"temperature_dependence",
       {CorrectionTerm::kTemperature, CorrectionTerm::kTemperatureQuadratic,
        CorrectionTerm::kOffset},
       true,
       true,
       Needs::kTemperature},
      {"stress_dependence",
       {CorrectionTerm::kStress, CorrectionTerm::kOffset},
       false,
       true,
       Needs::kStress},
      {"stress_dependence",
       {CorrectionTerm::kStressQuadratic, CorrectionTerm::kOffset},
       true,
       false,
       Needs::kStress},
      {"permittivity_nonlinearity",
       {CorrectionTerm::kDrivePolynomial},
       true,
       false,
       Needs::kNothing},
      // S ~ P^2: the model's D for field drive, the imposed D (the drive) for charge drive.
      {"electrostriction",
       {CorrectionTerm::kSensedQuadratic, CorrectionTerm::kOffset},
       false,
       true,
       Needs::kSensed},
      {"electrostriction",
       {CorrectionTerm::kDrivePolynomial, CorrectionTerm::kOffset},
       false,
       true,
       Needs::kChargeDrive},
  };
  return list;
}

double range_of(std::span<const double> x) {
  if (x.empty()) return 0.0;
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  return *hi - *lo;
}

// printf-style "%.3g", "%+.3g", "%.0f" and "%%" only (the math libraries do no stdio).
std::string format(const char* fmt, double a, double b = 0.0, double c = 0.0) {
  const double args[3] = {a, b, c};
  std::size_t next = 0;
  std::ostringstream out;
  for (const char* p = fmt; *p != '\0'; ++p) {
    if (*p != '%') {
      out << *p;
      continue;
    }
    ++p;
    if (*p == '%') {
      out << '%';
      continue;
    }
    const bool sign = *p == '+';
    if (sign) ++p;
    int digits = 6;
    if (*p == '.') {
      digits = 0;
      for (++p; *p >= '0' && *p <= '9'; ++p)
        digits = digits * 10 + (*p - '0');
    }
    const double v = next < 3 ? args[next++] : 0.0;
    if (sign && !(v < 0.0)) out << '+';
    if (*p == 'f') {
      out << std::fixed << std::setprecision(digits) << v << std::defaultfloat;
    } else {
      out << std::setprecision(std::max(digits, 1)) << v;
    }
  }
  return out.str();
}

struct ChannelData {
  std::string name;
  bool sensed{false};
  std::span<const double> recorded;
  std::vector<double> base;
  double coupling{0.0};                    // of the stress in the model's side
  std::span<const double> sensed_model{};  // the model's sensed response (electrostriction)
  bool affine{true};  // not the stress-hysteresis model: the response is G[x] + y0
};

// Which samples fit and which judge: sample k lies in block (k blocks) / n; even blocks fit,
// odd ones judge. Samples where the model gave no finite output do neither.
struct Rows {
  std::vector<bool> fit{};
  std::vector<bool> judge{};
  std::vector<std::size_t> block{};
  std::size_t blocks{0};
};

Rows make_rows(const std::vector<bool>& usable, std::size_t blocks) {
  const std::size_t n = usable.size();
  Rows r;
  r.blocks = blocks;
  r.fit.resize(n);
  r.judge.resize(n);
  r.block.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    r.block[k] = (k * blocks) / n;
    r.fit[k] = usable[k] && r.block[k] % 2 == 0;
    r.judge[k] = usable[k] && r.block[k] % 2 == 1;
  }
  return r;
}

// Per held-out block, the residual's energy before and after a candidate: the paired t-test
// over the blocks (statistics.hpp) says whether its gain is significant, the worst block whether
// it makes some stretch worse (a term that does will not carry over to new data either).
struct BlockShares {
  GainTest test{};
  double worst{0.0};  // the largest relative loss of one block, as a (negative) share
};

BlockShares block_explains(std::span<const double> recorded, const std::vector<double>& before,
                           const std::vector<double>& after, const Rows& rows) {
  std::vector<double> e0(rows.blocks, 0.0);
  std::vector<double> e1(rows.blocks, 0.0);
  for (std::size_t k = 0; k < recorded.size(); ++k) {
    if (!rows.judge[k]) continue;
    e0[rows.block[k]] += (recorded[k] - before[k]) * (recorded[k] - before[k]);
    e1[rows.block[k]] += (recorded[k] - after[k]) * (recorded[k] - after[k]);
  }
  std::vector<double> held0;
  std::vector<double> held1;
  BlockShares out;
  for (std::size_t b = 1; b < rows.blocks; b += 2) {
    if (!(e0[b] > 0.0)) continue;
    held0.push_back(e0[b]);
    held1.push_back(e1[b]);
  }
  // A block's loss relative to the larger of its own and the mean block's residual: a block
  // where the model is already nearly right is judged against the others, not its own noise.
  double mean = 0.0;
  for (const double e : held0)
    mean += e / static_cast<double>(held0.size());
  for (std::size_t i = 0; i < held0.size(); ++i)
    out.worst = std::min(out.worst, (held0[i] - held1[i]) / std::max(held0[i], mean));
  out.test = paired_gain_test(held0, held1);
  return out;
}

// The block test: a significant gain over the held-out blocks, none worse by `max_block_loss`.
bool passes_blocks(const BlockShares& shares, const Options& options) {
  return shares.test.significant && shares.worst >= -options.max_block_loss;
}

double sse_over(std::span<const double> recorded, const std::vector<double>& model,
                const std::vector<bool>& rows) {
  double sse = 0.0;
  for (std::size_t k = 0; k < recorded.size(); ++k) {
    if (!rows[k]) continue;
    const double e = recorded[k] - model[k];
    sse += e * e;
  }
  return sse;
}

// A channel's response to the drive alone, r = y - coupling T (y itself without a stress).
std::vector<double> response_to_drive(std::span<const double> y, double coupling,
                                      std::span<const double> stress) {
  std::vector<double> r(y.begin(), y.end());
  for (std::size_t k = 0; k < stress.size() && k < r.size(); ++k)
    r[k] -= coupling * stress[k];
  return r;
}

// Non-finite model outputs (a rejected first sample) are held at the last finite value so no
// filter state sees them; `usable` marks the samples that were finite.
std::vector<bool> hold_finite(std::vector<double>& y) {
  std::vector<bool> usable(y.size());
  double last = 0.0;
  for (const double v : y) {
    if (std::isfinite(v)) {
      last = v;
      break;
    }
  }
  for (std::size_t k = 0; k < y.size(); ++k) {
    usable[k] = std::isfinite(y[k]);
    if (usable[k]) {
      last = y[k];
    } else {
      y[k] = last;
    }
  }
  return usable;
}

// Time since the drive last moved by more than 5 % of its range, log10 seconds.
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

std::vector<double> rate_of(std::span<const double> x, double ts) {
  std::vector<double> out(x.size(), 0.0);
  for (std::size_t k = 1; k < x.size(); ++k)
    out[k] = (x[k] - x[k - 1]) / ts;
  if (out.size() > 1) out[0] = out[1];
  return out;
}

void describe(Finding& f, const ChannelCorrection& c, const ChannelData& ch, const Signals& s,
              const std::vector<double>& before, const std::vector<double>& after,
              const char* judged = "on held-out blocks") {
  const double range = range_of(ch.recorded);
  const double pct = range > 0.0 ? 100.0 / range : 0.0;
  double largest = 0.0;
  for (std::size_t k = 0; k < before.size(); ++k) {
    largest = std::max(largest, std::abs(after[k] - before[k]));
  }
  const std::string tail =
      format("; modelled, it removes %.0f %% of the residual variance ", 100.0 * f.explains) +
      judged + format(" (largest change %.2g %% of range)", largest * pct);
  const std::string& n = ch.name;
  if (f.effect == "offset") {
    f.evidence = "the recorded " + n +
                 format(" is offset by %.3g %% of its range and scaled by %.4g", c.offset * pct,
                        1.0 + c.gain) +
                 tail;
    f.feature_name = "model output";
    f.feature = before;
  } else if (f.effect == "charge_leakage") {
    if (c.leakage_tau_s > 0.0) {
      f.evidence = "the measured " + n +
                   format(
                       " forgets its charge with a time constant of %.3g s (charge amplifier "
                       "feedback or insulation resistance)",
                       c.leakage_tau_s) +
                   tail;
    } else {
      f.evidence = "the measured " + n +
                   format(
                       " loses charge in proportion to the integral of the field (a parallel "
                       "conductance of the stack: %.3g S/m)",
                       -c.drive_integral_per_s) +
                   tail;
    }
    f.feature_name = "time [s]";
    f.feature.resize(before.size());
    for (std::size_t k = 0; k < before.size(); ++k) {
      f.feature[k] = static_cast<double>(k) * s.sample_time;
    }
  } else if (f.effect == "delay") {
    f.evidence = "the recorded " + n +
                 format(" lags the model by %.3g samples (%.3g ms): channels sampled out of step",
                        c.delay_s / s.sample_time, c.delay_s * 1e3) +
                 tail;
    f.feature_name = "rate of the drive [1/s]";
    f.feature = rate_of(s.drive, s.sample_time);
  } else if (f.effect == "dynamics") {
    f.evidence = "the recorded " + n +
                 format(
                     " rings and lags at fast changes like a resonance at %.4g Hz with %.2g "
                     "damping (inertia of stack and load)",
                     c.dynamics_frequency_hz, c.dynamics_damping) +
                 tail;
    f.feature_name = "rate of the drive [1/s]";
    f.feature = rate_of(s.drive, s.sample_time);
  } else if (f.effect == "creep") {
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
    f.evidence = "after steps of the drive the recorded " + n +
                 format(" keeps moving by %.2g %% of the step per decade of time (",
                        100.0 * total / decades) +
                 span + (of_drive ? ", driven by the input" : ", driven by the model's output") +
                 ")" + tail;
    f.feature_name = "log10 time since the drive last stepped [s]";
    f.feature = log_time_since_step(s.drive, s.sample_time);
  } else if (f.effect == "hysteresis" || f.effect == "asymmetric_hysteresis") {
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
  } else if (f.effect == "temperature_dependence") {
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
  } else if (f.effect == "stress_dependence") {
    if (c.stress_quadratic_per_pa2 != 0.0) {
      const double t = std::max(std::abs(*std::max_element(s.stress.begin(), s.stress.end())),
                                std::abs(*std::min_element(s.stress.begin(), s.stress.end())));
      f.evidence = "the recorded " + n +
                   format(
                       " bends with the square of the stress (the coupling changes with "
                       "stress; %.3g %% of range at %.3g MPa)",
                       std::abs(c.stress_quadratic_per_pa2) * t * t * pct, t * 1e-6) +
                   tail;
    } else {
      f.evidence = "the coupling of " + n +
                   format(" changes with stress by %.3g %% per MPa over %.3g MPa",
                          100.0 * c.stress_gain_per_pa * 1e6, range_of(s.stress) * 1e-6) +
                   tail;
    }
    f.feature_name = "stress T [Pa]";
    f.feature.assign(s.stress.begin(), s.stress.end());
  } else if (f.effect == "permittivity_nonlinearity") {
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
  } else if (f.effect == "electrostriction") {
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
}

double coupling_of(const std::optional<models::SideModel>& side) {
  return (side && !side->linear_gains.empty()) ? side->linear_gains.front() : 0.0;
}

bool uses_term(const Candidate& c, CorrectionTerm t) {
  return std::find(c.terms.begin(), c.terms.end(), t) != c.terms.end();
}

bool applicable(const Candidate& c, const ChannelData& ch, const Signals& s, bool has_sensed,
                bool charge_drive) {
  if (ch.sensed ? !c.on_sensed : !c.on_strain) return false;
  const auto uses = [&](CorrectionTerm t) { return uses_term(c, t); };
  // T^2 on the sensed channel is solved with the sensor coupling; leakage is a charge's.
  if (uses(CorrectionTerm::kStressQuadratic) && ch.coupling == 0.0) return false;
  if ((uses(CorrectionTerm::kLeakage) || uses(CorrectionTerm::kDriveIntegral)) && charge_drive) {
    return false;
  }
  if (uses(CorrectionTerm::kCreep) && ch.sensed && !ch.affine) return false;
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

// Both forms of creep (lags of the response, lags of the drive): each bank present moves with
// the step (the drive raises D and S, so the drive's lags must push the same way).
bool creep_moves_with_the_step(const ChannelCorrection& c) {
  if (c.creep_eigenvalues.empty() && c.drive_creep_eigenvalues.empty()) return false;
  return (c.creep_eigenvalues.empty() ||
          lags_move_with_the_step(c.creep_eigenvalues, c.creep_weights)) &&
         (c.drive_creep_eigenvalues.empty() ||
          lags_move_with_the_step(c.drive_creep_eigenvalues, c.drive_creep_weights));
}

// An effect is named once per channel, in whichever of its forms fitted first.
bool named_already(const std::vector<const Candidate*>& used, const Candidate& c) {
  return std::any_of(used.begin(), used.end(), [&](const Candidate* u) {
    return std::string_view(u->effect) == std::string_view(c.effect);
  });
}

bool is_creep(const Candidate& c) {
  return uses_term(c, CorrectionTerm::kCreep) || uses_term(c, CorrectionTerm::kDriveCreep);
}

// The candidate brings a filter whose parameters are not chosen yet.
bool searches_filter(const Candidate& c, const ChannelCorrection& accepted) {
  for (const CorrectionTerm t : c.terms) {
    if ((t == CorrectionTerm::kLeakage && accepted.leakage_tau_s == 0.0) ||
        (t == CorrectionTerm::kDelay && accepted.delay_s == 0.0) ||
        (t == CorrectionTerm::kDynamics && accepted.dynamics_frequency_hz == 0.0)) {
      return true;
    }
  }
  return false;
}

// Coefficients and searched parameters a term adds: the parsimony tie-break.
std::size_t complexity(const std::vector<CorrectionTerm>& terms) {
  std::size_t n = 0;
  for (const CorrectionTerm t : terms) {
    switch (t) {
      case CorrectionTerm::kOffset:
      case CorrectionTerm::kDrivePolynomial:
      case CorrectionTerm::kDynamics:
        n += 2;
        break;
      case CorrectionTerm::kTemperature:
        n += 3;
        break;
      case CorrectionTerm::kCreep:
      case CorrectionTerm::kDriveCreep:
        n += 5;
        break;
      case CorrectionTerm::kTemperatureQuadratic:
        n += 2;
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

double segment_sse(std::span<const double> recorded, const std::vector<double>& model,
                   const Segment& seg) {
  double sse = 0.0;
  for (std::size_t k = seg.begin; k < seg.end; ++k) {
    sse += (recorded[k] - model[k]) * (recorded[k] - model[k]);
  }
  return sse;
}

bool overlaps(const Segment& a, const Segment& b) {
  return a.begin < b.end && b.begin < a.end;
}

// Held-out holds. Alternate time blocks cut each hold in two, so on a record of steps and holds a
// term that draws each hold's level from the other half of the same hold passes them without
// predicting anything new. Holding out whole holds (holds i, i + G, ... together, G <= 8 folds;
// the candidate refitted on everything else, identification::held_out_outputs) judges what it
// predicts for a hold it never saw.
//  - Creep lives in the holds after steps; in a record of a few holds that differ (large steps
//    and small ones, switching and none) the blocks judge it where it barely shows. It may pass on
//    the holds instead: judged on how the residual moves within each held-out hold (the hold's
//    mean removed: creep is the movement, the level is the static loop's), it must explain at
//    least `min_explains` of that movement over all holds and in two holds or more (not one by
//    chance).
//  - A hysteresis operator (generic: it can draw any level) must also do no harm there: the
//    residual over the held-out holds no larger than before.
// Either way no hold may get worse by more than `max_block_loss` of the larger of its own and
// the mean hold's residual (a hold that hardly moves is judged against the others, not against
// its own noise).
enum class HoldMeasure : std::uint8_t { kMovement, kLevel };

struct HoldJudgement {
  bool judged{false};
  HoldMeasure measure{HoldMeasure::kMovement};
  double explains{0.0};  // of the residual (or its movement) over the held-out holds
  double worst{0.0};     // the largest relative loss in one hold
  std::size_t improved{0};
  std::size_t holds{0};
};

HoldJudgement judge_on_holds(const identification::CorrectionSignals& cs,
                             const std::vector<CorrectionTerm>& terms,
                             const ChannelCorrection& start, const Rows& rows,
                             const std::vector<double>& current, const std::vector<Segment>& holds,
                             HoldMeasure measure, const Options& options) {
  constexpr std::size_t kMaxFolds = 8;
  HoldJudgement j;
  j.holds = holds.size();
  if (holds.size() < 3) return j;
  const std::size_t n = current.size();
  j.measure = measure;
  const std::size_t groups = std::min(holds.size(), kMaxFolds);
  std::vector<int> fold(n, -1);
  for (std::size_t h = 0; h < holds.size(); ++h) {
    for (std::size_t k = holds[h].begin; k < holds[h].end; ++k)
      fold[k] = static_cast<int>(h % groups);
  }
  std::vector<bool> usable(n);
  for (std::size_t k = 0; k < n; ++k)
    usable[k] = rows.fit[k] || rows.judge[k];
  std::vector<std::vector<double>> outputs;
  try {
    outputs = identification::held_out_outputs(cs, terms, start, usable, fold, groups);
  } catch (const std::invalid_argument&) {
    // No finite fit without some holds: the candidate cannot predict them.
    j.judged = true;
    j.explains = -std::numeric_limits<double>::infinity();
    return j;
  }
  std::vector<double> held_out(current);
  for (std::size_t h = 0; h < holds.size(); ++h) {
    const std::vector<double>& out = outputs[h % groups];
    for (std::size_t k = holds[h].begin; k < holds[h].end; ++k)
      held_out[k] = out[k];
  }
  // The residual's energy in a hold, about its mean in the hold when only movement counts.
  const auto energy = [&](const std::vector<double>& model, const Segment& h) {
    double sum = 0.0;
    double sum2 = 0.0;
    double count = 0.0;
    for (std::size_t k = h.begin; k < h.end; ++k) {
      if (!(rows.fit[k] || rows.judge[k])) continue;
      const double e = cs.recorded[k] - model[k];
      sum += e;
      sum2 += e * e;
      count += 1.0;
    }
    if (count == 0.0) return 0.0;
    return measure == HoldMeasure::kMovement ? sum2 - sum * sum / count : sum2;
  };
  std::vector<double> before(holds.size());
  std::vector<double> after(holds.size());
  double total_before = 0.0;
  double total_after = 0.0;
  for (std::size_t h = 0; h < holds.size(); ++h) {
    before[h] = energy(current, holds[h]);
    after[h] = energy(held_out, holds[h]);
    total_before += before[h];
    total_after += after[h];
  }
  if (!(total_before > 0.0)) return j;
  const double mean_before = total_before / static_cast<double>(holds.size());
  for (std::size_t h = 0; h < holds.size(); ++h) {
    if (before[h] > 0.0 && after[h] <= (1.0 - options.min_explains) * before[h]) ++j.improved;
    j.worst = std::max(j.worst, (after[h] - before[h]) / std::max(before[h], mean_before));
  }
  j.judged = true;
  j.explains = 1.0 - total_after / total_before;
  return j;
}

// Creep named on the holds (HoldMeasure::kMovement).
bool creep_passes_on_holds(const HoldJudgement& j, const Options& options) {
  return j.judged && j.measure == HoldMeasure::kMovement && j.explains >= options.min_explains &&
         j.improved >= 2 && j.worst <= options.max_block_loss;
}

// A hysteresis operator's levels on the holds (HoldMeasure::kLevel).
bool harmless_on_holds(const HoldJudgement& j, const Options& options) {
  return !j.judged || (j.explains >= 0.0 && j.worst <= options.max_block_loss);
}

// How a finding was judged, for its evidence.
std::string judged_on(const HoldJudgement& holds, const Options& options) {
  if (!creep_passes_on_holds(holds, options)) return "on held-out blocks";
  return format(
             "on held-out blocks; judged on held-out holds, where it explains %.0f %% of the "
             "movement within them and more than %.0f %% in %.0f",
             100.0 * holds.explains, 100.0 * options.min_explains,
             static_cast<double>(holds.improved)) +
         format(" of %.0f holds", static_cast<double>(holds.holds));
}

// Transients the block statistics cannot see (ringing after one fast step is a few samples of a
// long record): each strong residual segment not already explained is fitted on its own samples;
// a candidate is named when it removes most of the segment's residual with strong evidence for
// its extra parameters (BIC: n ln(SSE1/SSE0) + p ln n < -kLocalEvidence), and, refitted with
// the accepted terms on the fitting blocks, does not make the held-out blocks worse.
void local_pass(const ChannelData& ch, const identification::CorrectionSignals& cs,
                const Signals& s, const Rows& rows, double original_sse,
                std::vector<const Candidate*>& used, std::vector<CorrectionTerm>& accepted_terms,
                ChannelCorrection& accepted, std::vector<double>& current, bool charge_drive,
                std::vector<Finding>& findings) {
  constexpr double kLocalEvidence = 20.0;
  const std::size_t n = current.size();
  std::vector<double> residual(n);
  for (std::size_t k = 0; k < n; ++k)
    residual[k] = ch.recorded[k] - current[k];
  for (const Segment& seg : large_segments(residual, 3.0, 3)) {
    const bool known = std::any_of(findings.begin(), findings.end(), [&](const Finding& f) {
      return f.channel == ch.name &&
             std::any_of(f.where.begin(), f.where.end(),
                         [&](const Segment& w) { return overlaps(w, seg); });
    });
    const auto seg_n = static_cast<double>(seg.end - seg.begin);
    const double before = segment_sse(ch.recorded, current, seg);
    if (known || seg_n < 16.0 || !(before > 0.0)) continue;
    std::vector<bool> in_segment(n, false);
    for (std::size_t k = seg.begin; k < seg.end; ++k) {
      in_segment[k] = rows.fit[k] || rows.judge[k];
    }
    identification::CorrectionSignals on_current = cs;
    on_current.y = current;
    const Candidate* best = nullptr;
    ChannelCorrection best_found;
    double best_bic = -kLocalEvidence;
    for (const Candidate& c : candidates()) {
      if (named_already(used, c)) continue;
      if (!applicable(c, ch, s, !cs.sensed.empty(), charge_drive)) continue;
      // A hysteresis operator fitted to one stretch would bend to anything in it: transients
      // are named by specific physics only.
      if (c.generic) continue;
      identification::CorrectionFit local;
      try {
        local =
            identification::fit_correction(on_current, c.terms, ChannelCorrection{}, in_segment);
      } catch (const std::invalid_argument&) {
        continue;  // no finite fit in this stretch
      }
      if (is_creep(c) && !creep_moves_with_the_step(local.correction)) continue;
      const double after = segment_sse(ch.recorded, local.output, seg);
      const double bic = seg_n * std::log(std::max(after, 1e-300) / before) +
                         static_cast<double>(complexity(c.terms)) * std::log(seg_n);
      if (after <= 0.5 * before && bic < best_bic) {
        best_bic = bic;
        best = &c;
        best_found = local.correction;
      }
    }
    if (best == nullptr) continue;
    ChannelCorrection start = accepted;
    start.leakage_tau_s = std::max(start.leakage_tau_s, best_found.leakage_tau_s);
    start.delay_s = std::max(start.delay_s, best_found.delay_s);
    if (start.dynamics_frequency_hz == 0.0) {
      start.dynamics_frequency_hz = best_found.dynamics_frequency_hz;
      start.dynamics_damping = best_found.dynamics_damping;
    }
    const std::vector<CorrectionTerm> terms = merged(accepted_terms, best->terms);
    identification::CorrectionFit joint;
    try {
      joint = identification::fit_correction(cs, terms, start, rows.fit);
    } catch (const std::invalid_argument&) {
      continue;
    }
    const double held_before = sse_over(ch.recorded, current, rows.judge);
    const double held_after = sse_over(ch.recorded, joint.output, rows.judge);
    const double seg_after = segment_sse(ch.recorded, joint.output, seg);
    if (held_after > 1.02 * held_before || seg_after > 0.5 * before) continue;
    Finding f;
    f.effect = best->effect;
    f.channel = ch.name;
    // Contract: the share of the channel's residual variance (held-out blocks) it removes; the
    // share within its stretch goes into the evidence.
    f.explains = original_sse > 0.0 ? std::max(0.0, held_before - held_after) / original_sse : 0.0;
    f.where = {seg};
    const std::string judged =
        format("in the one stretch of %.3g s that shows it (%.0f %% there; BIC %.3g)",
               seg_n * s.sample_time, 100.0 * (1.0 - seg_after / before), best_bic);
    describe(f, joint.correction, ch, s, current, joint.output, judged.c_str());
    findings.push_back(std::move(f));
    used.push_back(best);
    accepted_terms = terms;
    accepted = joint.correction;
    current = joint.output;
  }
}

double rms(const std::vector<double>& x) {
  double sum = 0.0;
  for (const double v : x)
    sum += v * v;
  return x.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(x.size()));
}

// Where a residual that no candidate reduces lies: the stretches of large moving RMS, and their
// share of its energy (the whole record when it is spread evenly).
Unexplained unexplained_in(const std::string& channel, const std::vector<double>& residual,
                           double noise) {
  Unexplained u;
  u.channel = channel;
  u.residual_rms = rms(residual);
  u.noise_floor = noise;
  u.where = large_segments(residual, 1.5, 8);
  double total = 0.0;
  for (const double v : residual)
    total += v * v;
  double inside = 0.0;
  for (const Segment& seg : u.where) {
    for (std::size_t k = seg.begin; k < seg.end; ++k)
      inside += residual[k] * residual[k];
  }
  if (u.where.empty() || !(total > 0.0)) {
    u.where = {{0, residual.size()}};
    u.share = 1.0;
  } else {
    u.share = inside / total;
  }
  return u;
}

}  // namespace

const char* to_string(Verdict v) noexcept {
  switch (v) {
    case Verdict::kMismatch:
      return "mismatch";
    case Verdict::kUnexplained:
      return "unexplained";
    case Verdict::kConsistent:
      break;
  }
  return "consistent";
}

Outputs simulate(const models::TransducerModel& model, const Signals& s) {
  models::Simulation sim(model, models::RuntimeOptions{s.sample_time});
  Outputs out;
  const std::size_t n = s.drive.size();
  out.sensed.resize(n);
  out.strain.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    if (!s.temperature.empty()) sim.set_temperature(s.temperature[k]);
    const models::Simulation::Output o = sim.step(s.drive[k], s.stress.empty() ? 0.0 : s.stress[k]);
    out.sensed[k] = o.sensed;
    out.strain[k] = o.strain;
  }
  return out;
}

Result diagnose(const models::TransducerModel& model, const Signals& s, const Options& options) {
  const std::size_t n = s.drive.size();
  const auto sized = [n](std::span<const double> x) { return x.empty() || x.size() == n; };
  if (n < 100 || !sized(s.sensed) || !sized(s.strain) || !sized(s.stress) ||
      !sized(s.temperature) || !(s.sample_time > 0.0)) {
    throw std::invalid_argument(
        "diagnose: needs at least 100 samples of the drive, channels of equal length and a "
        "sample time");
  }
  models::TransducerModel base = model;
  base.sensed_correction.reset();
  base.strain_correction.reset();
  Outputs outputs = simulate(base, s);
  const bool field = model.drive() == models::Drive::kField;
  const bool has_sensor = model.sensor || (model.vectorial && model.vectorial->sensor);
  const bool has_actuator = model.actuator || (model.vectorial && model.vectorial->actuator);

  std::vector<ChannelData> channels;
  if (has_sensor && !s.sensed.empty()) {
    channels.push_back({field ? "D" : "E",
                        true,
                        s.sensed,
                        outputs.sensed,
                        coupling_of(model.sensor),
                        {},
                        !model.vectorial.has_value()});
  }
  if (has_actuator && !s.strain.empty()) {
    channels.push_back({"S", false, s.strain, outputs.strain, coupling_of(model.actuator)});
  }
  if (channels.empty()) {
    throw std::invalid_argument(
        "diagnose: the recording references none of the model's outputs (D or S)");
  }

  const std::size_t blocks = std::max<std::size_t>(2, options.blocks);
  // The channels hold their own copies; the electrostriction term reads the sensed channel's
  // response to the drive alone (D - d T: the polarization and the dielectric part).
  static_cast<void>(hold_finite(outputs.sensed));
  const std::vector<double> sensed_response =
      response_to_drive(outputs.sensed, coupling_of(model.sensor), s.stress);

  const std::vector<Segment> drive_holds = holds_of(s.drive);
  Result result;
  result.improved = base;
  for (ChannelData& ch : channels) {
    const Rows rows = make_rows(hold_finite(ch.base), blocks);
    ch.sensed_model = sensed_response;
    const std::vector<bool>& fit_rows = rows.fit;
    identification::CorrectionSignals cs;
    cs.y = ch.base;
    cs.recorded = ch.recorded;
    cs.drive = s.drive;
    cs.stress = s.stress;
    cs.temperature = s.temperature;
    cs.sensed = has_sensor ? std::span<const double>(sensed_response) : std::span<const double>();
    const std::vector<double> response = response_to_drive(ch.base, ch.coupling, s.stress);
    cs.response = response;
    cs.sample_time = s.sample_time;
    if (!s.temperature.empty()) cs.temperature_reference_degc = s.temperature[0];

    std::vector<CorrectionTerm> accepted_terms;
    ChannelCorrection accepted;
    std::vector<double> current = ch.base;
    std::vector<const Candidate*> used;
    double current_sse = sse_over(ch.recorded, current, rows.judge);
    const double original_sse = current_sse;

    for (std::size_t round = 0; round < options.max_effects && current_sse > 0.0; ++round) {
      struct Tried {
        const Candidate* candidate;
        identification::CorrectionFit fit;
        double explains;
        BlockShares blocks;  // over the held-out blocks
        HoldJudgement holds;
        std::vector<CorrectionTerm> terms;
        ChannelCorrection start;
        bool levels_judged;  // on held-out holds (hysteresis operators, when needed)
        bool in_pool{false};
      };
      std::vector<Tried> tried;
      for (const Candidate& c : candidates()) {
        if (named_already(used, c)) continue;
        if (!applicable(c, ch, s, has_sensor, !field)) continue;
        const std::vector<CorrectionTerm> terms = merged(accepted_terms, c.terms);
        ChannelCorrection start = accepted;
        try {
          if (searches_filter(c, accepted) && !accepted_terms.empty()) {
            // Search the new filter's parameters on what the accepted terms leave (few columns),
            // then refit every coefficient jointly with the filters fixed.
            identification::CorrectionSignals on_current = cs;
            on_current.y = current;
            const ChannelCorrection found =
                identification::fit_correction(on_current, c.terms, ChannelCorrection{}, fit_rows)
                    .correction;
            start.leakage_tau_s = std::max(start.leakage_tau_s, found.leakage_tau_s);
            start.delay_s = std::max(start.delay_s, found.delay_s);
            if (start.dynamics_frequency_hz == 0.0) {
              start.dynamics_frequency_hz = found.dynamics_frequency_hz;
              start.dynamics_damping = found.dynamics_damping;
            }
          }
          identification::CorrectionFit fit =
              identification::fit_correction(cs, terms, start, fit_rows);
          // A correction that must rescale the model's own output by more than 100 % is a
          // different model, not physics the model left out (re-identify instead).
          if (std::abs(fit.correction.gain) > options.max_gain) continue;
          if (is_creep(c) && !creep_moves_with_the_step(fit.correction)) continue;
          const double sse = sse_over(ch.recorded, fit.output, rows.judge);
          const double explains = 1.0 - sse / current_sse;
          const BlockShares shares = block_explains(ch.recorded, current, fit.output, rows);
          HoldJudgement holds;
          if (is_creep(c) && explains >= options.min_explains && !passes_blocks(shares, options)) {
            holds = judge_on_holds(cs, terms, start, rows, current, drive_holds,
                                   HoldMeasure::kMovement, options);
          }
          tried.push_back({&c, std::move(fit), explains, shares, holds, terms, start, false});
        } catch (const std::invalid_argument&) {
          continue;  // no finite fit of this candidate on these signals: not a candidate here
        }
      }
      if (tried.empty()) break;
      std::sort(tried.begin(), tried.end(),
                [](const Tried& a, const Tried& b) { return a.explains > b.explains; });
      // The held-out holds judge a hysteresis operator only when it would be named or listed
      // (each judgement costs a fit).
      const auto significant = [&](Tried& t) {
        if (t.explains < options.min_explains ||
            t.explains * current_sse < options.min_share * original_sse) {
          return false;
        }
        const bool in_blocks = passes_blocks(t.blocks, options);
        if (!t.candidate->generic) return in_blocks || creep_passes_on_holds(t.holds, options);
        if (!in_blocks) return false;
        if (!t.levels_judged) {
          t.levels_judged = true;
          t.holds = judge_on_holds(cs, t.terms, t.start, rows, current, drive_holds,
                                   HoldMeasure::kLevel, options);
        }
        return harmless_on_holds(t.holds, options);
      };
      // Specific physics first: when one is significant, a generic candidate competes only if
      // it leaves clearly less (a loop the specific terms merely resemble); otherwise it is an
      // alternative and may explain what is left in a later round.
      double specific_left = std::numeric_limits<double>::infinity();
      for (Tried& t : tried) {
        if (!t.candidate->generic && significant(t)) {
          specific_left = std::min(specific_left, 1.0 - t.explains);
        }
      }
      const auto competes = [&](const Tried& t) {
        return !t.candidate->generic || 1.0 - t.explains <= options.generic_ratio * specific_left;
      };
      // The pool: candidates that compete and are significant, best first (a generic candidate
      // that fails on the held-out holds leaves the others their chance).
      for (Tried& t : tried)
        t.in_pool = competes(t) && significant(t);
      const auto pool =
          static_cast<std::size_t>(std::stable_partition(tried.begin(), tried.end(),
                                                         [](const Tried& t) { return t.in_pool; }) -
                                   tried.begin());
      if (pool == 0) break;
      // Of the candidates explaining about as much as the best, the simplest.
      std::size_t chosen = 0;
      for (std::size_t i = 1; i < pool; ++i) {
        if (1.0 - tried[i].explains <= options.parsimony_ratio * (1.0 - tried.front().explains) &&
            complexity(tried[i].candidate->terms) < complexity(tried[chosen].candidate->terms)) {
          chosen = i;
        }
      }
      std::swap(tried[0], tried[chosen]);
      Tried& best = tried.front();

      Finding f;
      f.effect = best.candidate->effect;
      f.channel = ch.name;
      // Contract: the share of the channel's residual variance (held-out blocks) this physics
      // removes, so the shares of several findings add up.
      f.explains = original_sse > 0.0 ? best.explains * current_sse / original_sse : 0.0;
      for (std::size_t i = 1; i < tried.size(); ++i) {
        // Another form of the same effect is not an alternative (the finding names it anyway).
        if (tried[i].explains >= options.alternative_share * best.explains &&
            std::string_view(tried[i].candidate->effect) != std::string_view(f.effect) &&
            significant(tried[i])) {
          Finding other;
          other.effect = tried[i].candidate->effect;
          other.explains =
              original_sse > 0.0 ? tried[i].explains * current_sse / original_sse : 0.0;
          describe(other, tried[i].fit.correction, ch, s, current, tried[i].fit.output,
                   judged_on(tried[i].holds, options).c_str());
          f.alternatives.push_back({other.effect, other.explains, std::move(other.evidence)});
        }
      }
      std::vector<double> change(n);
      for (std::size_t k = 0; k < n; ++k)
        change[k] = best.fit.output[k] - current[k];
      f.where = large_segments(change, 1.5, 5);
      if (f.where.empty()) f.where = {{0, n}};  // spread evenly: the whole record
      const std::string judged = judged_on(best.holds, options);
      describe(f, best.fit.correction, ch, s, current, best.fit.output, judged.c_str());
      result.findings.push_back(std::move(f));

      accepted_terms = merged(accepted_terms, best.candidate->terms);
      accepted = best.fit.correction;
      used.push_back(best.candidate);
      current = best.fit.output;
      current_sse = sse_over(ch.recorded, current, rows.judge);
    }

    local_pass(ch, cs, s, rows, original_sse, used, accepted_terms, accepted, current, !field,
               result.findings);

    ChannelResult out;
    out.channel = ch.name;
    out.recorded.assign(ch.recorded.begin(), ch.recorded.end());
    out.before = ch.base;
    out.after = current;
    std::vector<double> residual(n);
    std::vector<double> residual_after(n);
    for (std::size_t k = 0; k < n; ++k) {
      residual[k] = ch.recorded[k] - ch.base[k];
      residual_after[k] = ch.recorded[k] - current[k];
    }
    out.located = large_segments(residual, 1.5, 8);
    out.noise_floor = noise_floor(residual);
    out.residual_rms = rms(residual_after);
    const bool named = std::any_of(result.findings.begin(), result.findings.end(),
                                   [&](const Finding& f) { return f.channel == ch.name; });
    if (!named && out.residual_rms > options.unexplained_ratio * out.noise_floor) {
      result.unexplained.push_back(unexplained_in(ch.name, residual_after, out.noise_floor));
    }
    out.test_before = correlation_test(residual, s.drive);
    out.test_after = correlation_test(residual_after, s.drive);
    result.channels.push_back(std::move(out));
    if (!accepted.empty()) {
      (ch.sensed ? result.improved.sensed_correction : result.improved.strain_correction) =
          accepted;
    }
  }
  result.mismatch = !result.findings.empty();
  if (result.mismatch) {
    result.verdict = Verdict::kMismatch;
  } else if (!result.unexplained.empty()) {
    result.verdict = Verdict::kUnexplained;
  }
  return result;
}

}  // namespace selfsense::diagnosis
