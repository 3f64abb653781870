#include "selfsense/identification/correction_fit.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace selfsense::identification {
namespace {

using models::ChannelCorrection;
using models::CorrectionStage;

double at(std::span<const double> s, std::size_t k, double fallback) noexcept {
  return s.empty() ? fallback : s[k];
}

// One column per coefficient, in the order apply_coefficients() reads them back.
struct Columns {
  std::vector<std::vector<double>> phi{};
  std::vector<double> creep_eigenvalues{};
  std::vector<double> drive_creep_eigenvalues{};
  std::vector<double> play_thresholds{};
  std::vector<double> hinge_thresholds{};
  std::vector<double> hinge_levels{};
  bool stress_varies{false};  // the temperature terms carry their stress columns
  bool mode_shares{false};    // kSecondMode: the mode shares' columns follow phi (filters)
};

constexpr std::size_t kCorrectionPlays = 8;
constexpr std::size_t kHingeLevels = 3;

// The drive's plays on an even grid up to half its range (a wider play would never move after
// one sweep), each run from rest at the first sample: one column per play, sample-major.
std::vector<std::vector<double>> drive_plays(std::span<const double> x,
                                             std::vector<double>& thresholds) {
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  const double range = *hi - *lo;
  thresholds.clear();
  std::vector<std::vector<double>> out;
  if (!(range > 0.0)) return out;
  for (std::size_t i = 1; i <= kCorrectionPlays; ++i) {
    const double r =
        0.5 * range * static_cast<double>(i) / static_cast<double>(kCorrectionPlays + 1);
    thresholds.push_back(r);
    std::vector<double> p(x.size());
    double state = x[0];
    for (std::size_t k = 0; k < x.size(); ++k) {
      state = std::min(std::max(state, x[k] - r), x[k] + r);
      p[k] = state;
    }
    out.push_back(std::move(p));
  }
  return out;
}

std::vector<double> log_spaced(double from, double to, std::size_t per_decade) {
  std::vector<double> out;
  if (!(from > 0.0 && to > from)) return out;
  const double step = 1.0 / static_cast<double>(per_decade);
  const double first = std::log10(from);
  const auto count = static_cast<std::size_t>(std::floor((std::log10(to) - first) / step + 1e-9));
  for (std::size_t i = 0; i <= count; ++i) {
    out.push_back(std::pow(10.0, first + static_cast<double>(i) * step));
  }
  return out;
}

// One lag per decade from 1/(20 Ts) (at most 1e3 1/s) down to 3 / duration.
std::vector<double> lag_eigenvalues(std::size_t n, double ts) {
  const double duration = static_cast<double>(n) * ts;
  const double fastest = std::min(1.0 / (20.0 * ts), 1.0e3);
  std::vector<double> out = log_spaced(3.0 / duration, fastest, 1);
  if (out.size() > models::kMaxCorrectionCreep) {
    out.erase(out.begin(), out.end() - static_cast<std::ptrdiff_t>(models::kMaxCorrectionCreep));
  }
  return out;
}

// First-order lags of a signal, z[k] = z[k-1] + (1 - exp(-lambda Ts)) (v[k] - z[k-1]) from
// z = v[0], each minus v[0]: one column per eigenvalue.
template <typename Value>
void add_lags(Columns& c, std::size_t n, double ts, const std::vector<double>& eigenvalues,
              Value&& value) {
  const double v0 = value(0);
  for (const double lambda : eigenvalues) {
    const double a = -std::expm1(-lambda * ts);
    std::vector<double> col(n);
    double z = v0;
    for (std::size_t k = 0; k < n; ++k) {
      z += a * (value(k) - z);
      col[k] = z - v0;
    }
    c.phi.push_back(std::move(col));
  }
}

bool has_term(std::span<const CorrectionTerm> terms, CorrectionTerm t) {
  return std::find(terms.begin(), terms.end(), t) != terms.end();
}

Columns make_columns(const CorrectionSignals& s, std::span<const CorrectionTerm> terms) {
  const std::size_t n = s.y.size();
  Columns c;
  const auto add = [&](auto&& f) {
    std::vector<double> col(n);
    for (std::size_t k = 0; k < n; ++k)
      col[k] = f(k);
    c.phi.push_back(std::move(col));
  };
  const auto dtheta = [&](std::size_t k) {
    return at(s.temperature, k, s.temperature_reference_degc) - s.temperature_reference_degc;
  };
  // A stress that never moves leaves its temperature columns zero (a rank the solve would lose).
  c.stress_varies = !s.stress.empty() && std::any_of(s.stress.begin(), s.stress.end(),
                                                     [&](double v) { return v != s.stress[0]; });
  for (const CorrectionTerm t : terms) {
    switch (t) {
      case CorrectionTerm::kOffset:
        add([&](std::size_t k) { return s.y[k]; });
        add([](std::size_t) { return 1.0; });
        break;
      case CorrectionTerm::kTemperature:
        add([&](std::size_t k) { return dtheta(k) * s.y[k]; });
        add([&](std::size_t k) { return dtheta(k); });
        add([&](std::size_t k) { return dtheta(k) * s.drive[k]; });
        // With the output and the drive, the stress's own column lets the coupling move apart
        // from the loop and the permittivity (each scales its own part of y).
        if (c.stress_varies) add([&](std::size_t k) { return dtheta(k) * s.stress[k]; });
        break;
      case CorrectionTerm::kTemperatureQuadratic:
        add([&](std::size_t k) { return dtheta(k) * dtheta(k) * s.y[k]; });
        add([&](std::size_t k) { return dtheta(k) * dtheta(k); });
        add([&](std::size_t k) { return dtheta(k) * dtheta(k) * s.drive[k]; });
        if (c.stress_varies) {
          add([&](std::size_t k) { return dtheta(k) * dtheta(k) * s.stress[k]; });
        }
        break;
      case CorrectionTerm::kStress:
        add([&](std::size_t k) { return at(s.stress, k, 0.0) * at(s.response, k, s.y[k]); });
        // The model's coupling was identified at the recording's mean stress T0: a coupling
        // d (1 + k T) leaves k (T - T0) r, which T r alone can only reach with the gain on y = r +
        // coupling T and the stress's own column beside it (with kStressDrive, that adds it).
        if (!has_term(terms, CorrectionTerm::kStressDrive)) {
          add([&](std::size_t k) { return at(s.stress, k, 0.0); });
        }
        break;
      case CorrectionTerm::kDriveCreep:
        c.drive_creep_eigenvalues = lag_eigenvalues(n, s.sample_time);
        add_lags(c, n, s.sample_time, c.drive_creep_eigenvalues,
                 [&](std::size_t k) { return s.drive[k]; });
        break;
      case CorrectionTerm::kDriveIntegral: {
        std::vector<double> col(n);
        double q = 0.0;
        for (std::size_t k = 0; k < n; ++k) {
          if (k > 0) q += s.sample_time * s.drive[k];
          col[k] = q;
        }
        c.phi.push_back(std::move(col));
        break;
      }
      case CorrectionTerm::kStressQuadratic:
        add([&](std::size_t k) {
          const double stress = at(s.stress, k, 0.0);
          return stress * stress;
        });
        break;
      case CorrectionTerm::kStressDrive:
        add([&](std::size_t k) { return at(s.stress, k, 0.0) * s.drive[k]; });
        add([&](std::size_t k) { return at(s.stress, k, 0.0); });
        break;
      case CorrectionTerm::kDrivePolynomial:
        add([&](std::size_t k) { return s.drive[k] * s.drive[k]; });
        add([&](std::size_t k) { return s.drive[k] * s.drive[k] * s.drive[k]; });
        break;
      case CorrectionTerm::kSensedQuadratic:
        add([&](std::size_t k) {
          const double d = at(s.sensed, k, 0.0);
          return d * d;
        });
        break;
      case CorrectionTerm::kCreep:
        c.creep_eigenvalues = lag_eigenvalues(n, s.sample_time);
        add_lags(c, n, s.sample_time, c.creep_eigenvalues,
                 [&](std::size_t k) { return at(s.response, k, s.y[k]); });
        break;
      case CorrectionTerm::kHysteresis:
      case CorrectionTerm::kAsymmetricHysteresis: {
        // The asymmetric bank contains the plain one: one bank when both are asked for.
        if (t == CorrectionTerm::kHysteresis &&
            has_term(terms, CorrectionTerm::kAsymmetricHysteresis)) {
          break;
        }
        // A PI operator of the drive: its linear play (x itself) and the plays beside it.
        add([&](std::size_t k) { return s.drive[k]; });
        const std::vector<std::vector<double>> plays = drive_plays(s.drive, c.play_thresholds);
        for (const auto& p : plays)
          add([&](std::size_t k) { return p[k] - s.drive[k]; });
        if (t == CorrectionTerm::kHysteresis || plays.empty()) break;
        // Hinges at levels spread over each play's span [lo + r, hi - r] (and x's own).
        const auto [lo, hi] = std::minmax_element(s.drive.begin(), s.drive.end());
        for (std::size_t i = 0; i <= plays.size(); ++i) {
          const double r = i == 0 ? 0.0 : c.play_thresholds[i - 1];
          const std::span<const double> p =
              i == 0 ? s.drive : std::span<const double>(plays[i - 1]);
          for (std::size_t j = 1; j <= kHingeLevels; ++j) {
            const double level = *lo + r +
                                 (*hi - *lo - 2.0 * r) * static_cast<double>(j) /
                                     static_cast<double>(kHingeLevels + 1);
            c.hinge_thresholds.push_back(r);
            c.hinge_levels.push_back(level);
            add([&](std::size_t k) { return std::max(p[k] - level, 0.0); });
          }
        }
        break;
      }
      case CorrectionTerm::kSecondMode:
        c.mode_shares = has_term(terms, CorrectionTerm::kDynamics);
        break;  // its columns depend on the filters (fill_regressors)
      case CorrectionTerm::kDynamics:
      case CorrectionTerm::kLeakage:
      case CorrectionTerm::kDelay:
        break;  // filters: searched, not regressors
    }
  }
  return c;
}

// Coefficients back into a correction, in the order of make_columns().
void apply_coefficients(std::span<const CorrectionTerm> terms, const Columns& columns,
                        const Eigen::VectorXd& c, ChannelCorrection& out) {
  Eigen::Index i = 0;
  for (const CorrectionTerm t : terms) {
    switch (t) {
      case CorrectionTerm::kOffset:
        out.gain = c[i++];
        out.offset = c[i++];
        break;
      case CorrectionTerm::kTemperature:
        out.temperature_gain_per_k = c[i++];
        out.temperature_offset_per_k = c[i++];
        out.temperature_drive_per_k = c[i++];
        out.temperature_stress_per_k = columns.stress_varies ? c[i++] : 0.0;
        break;
      case CorrectionTerm::kTemperatureQuadratic:
        out.temperature_gain_per_k2 = c[i++];
        out.temperature_offset_per_k2 = c[i++];
        out.temperature_drive_per_k2 = c[i++];
        out.temperature_stress_per_k2 = columns.stress_varies ? c[i++] : 0.0;
        break;
      case CorrectionTerm::kStress:
        out.stress_gain_per_pa = c[i++];
        if (!has_term(terms, CorrectionTerm::kStressDrive)) out.stress_linear_per_pa = c[i++];
        break;
      case CorrectionTerm::kDriveCreep:
        out.drive_creep_eigenvalues = columns.drive_creep_eigenvalues;
        out.drive_creep_weights.clear();
        for (std::size_t j = 0; j < columns.drive_creep_eigenvalues.size(); ++j) {
          out.drive_creep_weights.push_back(c[i++]);
        }
        break;
      case CorrectionTerm::kDriveIntegral:
        out.drive_integral_per_s = c[i++];
        break;
      case CorrectionTerm::kStressQuadratic:
        out.stress_quadratic_per_pa2 = c[i++];
        break;
      case CorrectionTerm::kStressDrive:
        out.stress_drive_per_pa = c[i++];
        out.stress_linear_per_pa = c[i++];
        break;
      case CorrectionTerm::kDrivePolynomial:
        out.drive_quadratic = c[i++];
        out.drive_cubic = c[i++];
        break;
      case CorrectionTerm::kSensedQuadratic:
        out.sensed_quadratic = c[i++];
        break;
      case CorrectionTerm::kCreep:
        out.creep_eigenvalues = columns.creep_eigenvalues;
        out.creep_weights.clear();
        for (std::size_t j = 0; j < columns.creep_eigenvalues.size(); ++j) {
          out.creep_weights.push_back(c[i++]);
        }
        break;
      case CorrectionTerm::kHysteresis:
      case CorrectionTerm::kAsymmetricHysteresis:
        if (t == CorrectionTerm::kHysteresis &&
            has_term(terms, CorrectionTerm::kAsymmetricHysteresis)) {
          break;
        }
        out.drive_linear = c[i++];
        out.hysteresis_thresholds = columns.play_thresholds;
        out.hysteresis_weights.clear();
        for (std::size_t j = 0; j < columns.play_thresholds.size(); ++j)
          out.hysteresis_weights.push_back(c[i++]);
        if (t == CorrectionTerm::kHysteresis) break;
        out.hinge_thresholds = columns.hinge_thresholds;
        out.hinge_levels = columns.hinge_levels;
        out.hinge_weights.clear();
        for (std::size_t j = 0; j < columns.hinge_thresholds.size(); ++j)
          out.hinge_weights.push_back(c[i++]);
        break;
      default:
        break;
    }
  }
}

// A mode's grid: 8 frequencies per decade from 1/500 of Nyquist (10 cycles of the record at
// least) to 0.8 Nyquist, each at 7 dampings.
std::vector<std::pair<double, double>> mode_grid(double ts, double duration) {
  const double nyquist = 0.5 / ts;
  std::vector<std::pair<double, double>> out;
  for (const double f : log_spaced(std::max(nyquist / 500.0, 10.0 / duration), 0.8 * nyquist, 8)) {
    for (const double zeta : {0.01, 0.02, 0.04, 0.08, 0.15, 0.3, 0.6})
      out.emplace_back(f, zeta);
  }
  return out;
}

// The filter settings to try: the given ones, or a grid for each searched filter.
std::vector<ChannelCorrection> filter_grid(const CorrectionSignals& s,
                                           std::span<const CorrectionTerm> terms,
                                           const ChannelCorrection& start) {
  const auto has = [&](CorrectionTerm t) {
    return std::find(terms.begin(), terms.end(), t) != terms.end();
  };
  ChannelCorrection fixed;
  fixed.dynamics_frequency_hz = start.dynamics_frequency_hz;
  fixed.dynamics_damping = start.dynamics_damping;
  if (has(CorrectionTerm::kSecondMode)) {
    fixed.dynamics2_frequency_hz = start.dynamics2_frequency_hz;
    fixed.dynamics2_damping = start.dynamics2_damping;
  }
  fixed.leakage_tau_s = start.leakage_tau_s;
  fixed.delay_s = start.delay_s;
  std::vector<ChannelCorrection> grid{fixed};
  const auto expand = [&](auto&& set, const std::vector<double>& values) {
    std::vector<ChannelCorrection> next;
    for (const ChannelCorrection& g : grid) {
      for (const double v : values) {
        ChannelCorrection c = g;
        set(c, v);
        next.push_back(c);
      }
    }
    grid = std::move(next);
  };
  const double ts = s.sample_time;
  const double duration = static_cast<double>(s.y.size()) * ts;
  if (has(CorrectionTerm::kLeakage) && start.leakage_tau_s == 0.0) {
    expand([](ChannelCorrection& c, double v) { c.leakage_tau_s = v; },
           log_spaced(std::max(20.0 * ts, duration / 1000.0), 100.0 * duration, 4));
  }
  if (has(CorrectionTerm::kDelay) && start.delay_s == 0.0) {
    // Quarter samples up to 4, whole samples up to 16, then every 4 (in samples).
    std::vector<double> delays;
    for (int q = 1; q <= 16; ++q)
      delays.push_back(0.25 * q * ts);
    for (int d = 5; d <= 16; ++d)
      delays.push_back(d * ts);
    for (int d = 20; d <= static_cast<int>(models::kMaxCorrectionDelaySamples); d += 4) {
      delays.push_back(d * ts);
    }
    expand([](ChannelCorrection& c, double v) { c.delay_s = v; }, delays);
  }
  if (has(CorrectionTerm::kDynamics) && start.dynamics_frequency_hz == 0.0) {
    std::vector<ChannelCorrection> next;
    for (const ChannelCorrection& g : grid) {
      for (const auto& [f, zeta] : mode_grid(ts, duration)) {
        ChannelCorrection c = g;
        c.dynamics_frequency_hz = f;
        c.dynamics_damping = zeta;
        next.push_back(c);
      }
    }
    grid = std::move(next);
  }
  return grid;
}

// The second mode's settings to try beside the chosen filters (the first mode fixed): the
// first's grid, less its own frequency.
std::vector<ChannelCorrection> second_mode_grid(const CorrectionSignals& s,
                                                const ChannelCorrection& chosen) {
  std::vector<ChannelCorrection> out;
  const double duration = static_cast<double>(s.y.size()) * s.sample_time;
  for (const auto& [f, zeta] : mode_grid(s.sample_time, duration)) {
    if (std::abs(std::log(f / chosen.dynamics_frequency_hz)) < 0.05) continue;
    ChannelCorrection c = chosen;
    c.dynamics2_frequency_hz = f;
    c.dynamics2_damping = zeta;
    out.push_back(c);
  }
  return out;
}

// Coordinate search around the best grid point of every searched filter parameter: each is
// multiplied and divided by shrinking factors while the fitting error falls.
template <typename Evaluate>
void refine(const CorrectionSignals& s, std::span<const CorrectionTerm> terms,
            const ChannelCorrection& start, const ChannelCorrection& best, Evaluate&& evaluate) {
  const auto has = [&](CorrectionTerm t) {
    return std::find(terms.begin(), terms.end(), t) != terms.end();
  };
  std::vector<double ChannelCorrection::*> params;
  if (has(CorrectionTerm::kLeakage) && start.leakage_tau_s == 0.0) {
    params.push_back(&ChannelCorrection::leakage_tau_s);
  }
  if (has(CorrectionTerm::kDelay) && start.delay_s == 0.0) {
    params.push_back(&ChannelCorrection::delay_s);
  }
  if (has(CorrectionTerm::kDynamics) && start.dynamics_frequency_hz == 0.0) {
    params.push_back(&ChannelCorrection::dynamics_frequency_hz);
    params.push_back(&ChannelCorrection::dynamics_damping);
  }
  // The second mode once it is chosen (second_mode_grid), jointly with the rest.
  if (has(CorrectionTerm::kSecondMode) && start.dynamics2_frequency_hz == 0.0 &&
      best.dynamics2_frequency_hz > 0.0) {
    params.push_back(&ChannelCorrection::dynamics2_frequency_hz);
    params.push_back(&ChannelCorrection::dynamics2_damping);
  }
  if (params.empty()) return;
  ChannelCorrection current = best;
  for (const double factor : {1.2, 1.06, 1.02, 1.005}) {
    for (int pass = 0; pass < 6; ++pass) {
      bool improved = false;
      for (double ChannelCorrection::*p : params) {
        for (const double f : {factor, 1.0 / factor}) {
          ChannelCorrection trial = current;
          trial.*p *= f;
          if (trial.delay_s >
              static_cast<double>(models::kMaxCorrectionDelaySamples) * s.sample_time) {
            continue;
          }
          bool better = false;
          try {
            better = evaluate(trial);
          } catch (const std::invalid_argument&) {
            better = false;  // outside what the sample time allows
          }
          if (better) {
            current = trial;
            improved = true;
            break;
          }
        }
      }
      if (!improved) break;
    }
  }
}

// F[x] for each column x of `in`, into the matching `out` (resized; reused between grid points,
// so a search allocates its columns once): each column through its own stage of the filters
// alone (a column is filtered, not corrected). The columns advance together, sample by sample:
// each stage's recursion waits on its own last output, so the stages' steps overlap in the
// processor (the same arithmetic as one column at a time).
void filter_all(std::span<const std::span<const double>> in, const ChannelCorrection& filters,
                double ts, std::span<std::vector<double>> out) {
  ChannelCorrection only;  // the filters without any term
  only.dynamics_frequency_hz = filters.dynamics_frequency_hz;
  only.dynamics_damping = filters.dynamics_damping;
  only.leakage_tau_s = filters.leakage_tau_s;
  only.delay_s = filters.delay_s;
  const std::size_t n = in.empty() ? 0 : in.front().size();
  std::vector<CorrectionStage> stages(in.size(), CorrectionStage(only, ts));  // checks `only`
  std::vector<double*> to(in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    out[i].resize(n);
    to[i] = out[i].data();
  }
  if (n > 0 && only.dynamics_frequency_hz > 0.0 && only.leakage_tau_s == 0.0 &&
      only.delay_s == 0.0) {
    // A mode alone: the stage's recursion written out where it inlines (a mode's search filters
    // the record once per setting tried), in the stage's order of operations: the same doubles.
    const models::ModeCoefficients m =
        models::mode_coefficients(only.dynamics_frequency_hz, only.dynamics_damping, ts);
    const double b1 = 2.0 * m.b0;
    for (std::size_t i = 0; i < in.size(); ++i) {
      const std::span<const double> x = in[i];
      double* y = to[i];
      double v1 = x[0];
      double v2 = x[0];
      double w1 = x[0];
      double w2 = x[0];
      y[0] = x[0];
      for (std::size_t k = 1; k < n; ++k) {
        const double v = x[k];
        const double w = m.b0 * v + b1 * v1 + m.b0 * v2 - m.a1 * w1 - m.a2 * w2;
        v2 = v1;
        v1 = v;
        w2 = w1;
        w1 = w;
        y[k] = w;
      }
    }
    return;
  }
  for (std::size_t k = 0; k < n; ++k) {
    for (std::size_t i = 0; i < in.size(); ++i)
      to[i][k] = stages[i].filter(in[i][k]);
  }
}

struct Solved {
  Eigen::VectorXd coefficients{};
  double sse{std::numeric_limits<double>::infinity()};
};

// The normal equations of least squares: G = A'A, b = A'y over some rows.
struct Normal {
  Eigen::MatrixXd g;
  Eigen::VectorXd b;
  double energy{0.0};  // y'y
};

Normal zero_normal(Eigen::Index p) {
  return {Eigen::MatrixXd::Zero(p, p), Eigen::VectorXd::Zero(p), 0.0};
}

// Adds sample k to the normal equations (G in its lower triangle).
void accumulate(Normal& n, std::span<const double> target,
                std::span<const std::span<const double>> columns, std::size_t k,
                Eigen::VectorXd& row) {
  const Eigen::Index p = row.size();
  for (Eigen::Index i = 0; i < p; ++i)
    row[i] = columns[static_cast<std::size_t>(i)][k];
  // G += row row' in the lower triangle, written out: Eigen's rank-one update costs more in
  // its dispatch than in these few products (the same products and sums).
  double* g = n.g.data();
  for (Eigen::Index i = 0; i < p; ++i) {
    const double v = row[i];
    double* column = g + i * p;
    for (Eigen::Index j = i; j < p; ++j)
      column[j] += v * row[j];
  }
  n.b += row * target[k];
  n.energy += target[k] * target[k];
}

Solved solve_normal(Normal n) {
  const Eigen::Index p = n.b.size();
  Solved out;
  if (p == 0) {
    out.sse = n.energy;
    out.coefficients = Eigen::VectorXd();
    return out;
  }
  const Eigen::MatrixXd g = n.g.selfadjointView<Eigen::Lower>();
  Eigen::VectorXd scale = g.diagonal().cwiseSqrt();
  for (Eigen::Index i = 0; i < p; ++i) {
    if (!(scale[i] > 0.0)) scale[i] = 1.0;
  }
  const Eigen::MatrixXd gs =
      scale.cwiseInverse().asDiagonal() * g * scale.cwiseInverse().asDiagonal();
  // Minimum-norm solution: directions the rows cannot tell apart (columns nearly collinear on
  // these samples, e.g. the drive and a model output proportional to it) get no weight, rather
  // than large opposite weights that cancel here and nowhere else.
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(gs);
  const Eigen::VectorXd& lambda = eig.eigenvalues();
  const double floor = 1e-10 * std::max(lambda.maxCoeff(), 0.0);
  const Eigen::VectorXd projected = eig.eigenvectors().transpose() * n.b.cwiseQuotient(scale);
  Eigen::VectorXd weighted = Eigen::VectorXd::Zero(p);
  for (Eigen::Index i = 0; i < p; ++i) {
    if (lambda[i] > floor) weighted[i] = projected[i] / lambda[i];
  }
  const Eigen::VectorXd theta = eig.eigenvectors() * weighted;
  out.coefficients = theta.cwiseQuotient(scale);
  out.sse = std::max(
      0.0, n.energy - 2.0 * out.coefficients.dot(n.b) + out.coefficients.dot(g * out.coefficients));
  return out;
}

// The fitting rows the least squares read (kCorrectionFitRows): every m-th of them.
std::vector<bool> least_squares_rows(const std::vector<bool>& fit_rows) {
  const auto count = static_cast<std::size_t>(std::count(fit_rows.begin(), fit_rows.end(), true));
  if (count <= kCorrectionFitRows) return fit_rows;
  const std::size_t step = (count + kCorrectionFitRows - 1) / kCorrectionFitRows;
  std::vector<bool> kept(fit_rows.size(), false);
  std::size_t seen = 0;
  for (std::size_t k = 0; k < fit_rows.size(); ++k) {
    if (fit_rows[k] && seen++ % step == 0) kept[k] = true;
  }
  return kept;
}

Solved solve(std::span<const double> target, std::span<const std::span<const double>> columns,
             const std::vector<bool>& rows) {
  const auto p = static_cast<Eigen::Index>(columns.size());
  Normal n = zero_normal(p);
  Eigen::VectorXd row(p);
  for (std::size_t k = 0; k < target.size(); ++k) {
    if (rows[k]) accumulate(n, target, columns, k, row);
  }
  return solve_normal(std::move(n));
}

// The regressors of a fit with the given filters: the columns (filtered when there are filters)
// and the target recorded - F[y]. `columns` views `owned` (or the unfiltered columns): a move
// keeps those views valid, a copy would not, so there is none. With mode shares the last
// columns are R[y] - F[y] (a direct path) and, with a second mode, F2[y] - F[y].
struct Regressors {
  Regressors() = default;
  Regressors(const Regressors&) = delete;
  Regressors& operator=(const Regressors&) = delete;
  Regressors(Regressors&&) = default;
  Regressors& operator=(Regressors&&) = default;
  ~Regressors() = default;

  std::vector<std::vector<double>> owned{};
  std::vector<std::vector<double>> shares{};  // R[y] - F[y], F2[y] - F[y]
  std::vector<std::span<const double>> columns{};
  std::vector<double> target{};
  // The filters `owned` and `target` were computed for (the second mode's search changes only
  // F2, so it reuses them); none yet when empty.
  std::vector<ChannelCorrection> filled_for{};
};

// The filters without a second mode: what F and R depend on.
ChannelCorrection first_filters(const ChannelCorrection& filters) {
  ChannelCorrection c;
  c.dynamics_frequency_hz = filters.dynamics_frequency_hz;
  c.dynamics_damping = filters.dynamics_damping;
  c.leakage_tau_s = filters.leakage_tau_s;
  c.delay_s = filters.delay_s;
  return c;
}

void filter_one(std::span<const double> in, const ChannelCorrection& filters, double ts,
                std::vector<double>& out) {
  const std::span<const double> one[] = {in};
  filter_all(one, filters, ts, std::span<std::vector<double>>(&out, 1));
}

// Fills `r` for these filters, reusing its buffers (a filter search evaluates many settings).
void fill_regressors(const CorrectionSignals& s, const Columns& columns,
                     const ChannelCorrection& filters, Regressors& r) {
  // Unfiltered columns are read in place (a 1e6-sample recording: no copies per evaluation).
  const ChannelCorrection first = first_filters(filters);
  const bool any_filter = !first.empty();
  const bool shares = columns.mode_shares && filters.dynamics_frequency_hz > 0.0;
  const std::size_t n = s.y.size();
  const bool reuse = !r.filled_for.empty() && r.filled_for.front() == first;
  if (!reuse) {
    r.filled_for.clear();  // until the filters below have run (they may throw)
    if (any_filter) {
      std::vector<std::span<const double>> in(columns.phi.begin(), columns.phi.end());
      in.emplace_back(s.y);
      r.owned.resize(in.size());  // the last one: F[y]
      filter_all(in, first, s.sample_time, r.owned);
    }
    r.target.assign(s.recorded.begin(), s.recorded.end());
    const std::span<const double> fy = any_filter ? std::span<const double>(r.owned.back()) : s.y;
    for (std::size_t k = 0; k < n; ++k)
      r.target[k] -= fy[k];
    if (shares) {
      r.shares.resize(2);
      ChannelCorrection rest = first;
      rest.dynamics_frequency_hz = 0.0;
      rest.dynamics_damping = 0.0;
      filter_one(s.y, rest, s.sample_time, r.shares[0]);
      for (std::size_t k = 0; k < n; ++k)
        r.shares[0][k] -= fy[k];
    }
    r.filled_for.assign(1, first);
  }
  r.columns.clear();
  r.columns.reserve(columns.phi.size() + 2);
  for (std::size_t i = 0; i < columns.phi.size(); ++i) {
    r.columns.emplace_back(any_filter ? std::span<const double>(r.owned[i])
                                      : std::span<const double>(columns.phi[i]));
  }
  if (!shares) return;
  r.columns.emplace_back(r.shares[0]);
  if (filters.dynamics2_frequency_hz > 0.0) {
    ChannelCorrection second = first;
    second.dynamics_frequency_hz = filters.dynamics2_frequency_hz;
    second.dynamics_damping = filters.dynamics2_damping;
    filter_one(s.y, second, s.sample_time, r.shares[1]);
    const std::vector<double>& fy = r.owned.back();
    for (std::size_t k = 0; k < n; ++k)
      r.shares[1][k] -= fy[k];
    r.columns.emplace_back(r.shares[1]);
  }
}

Regressors regressors(const CorrectionSignals& s, const Columns& columns,
                      const ChannelCorrection& filters) {
  Regressors r;
  fill_regressors(s, columns, filters, r);
  return r;
}

void check_signals(const CorrectionSignals& s, const std::vector<bool>& fit_rows) {
  const std::size_t n = s.y.size();
  if (n == 0 || s.recorded.size() != n || s.drive.size() != n || fit_rows.size() != n ||
      (!s.stress.empty() && s.stress.size() != n) ||
      (!s.temperature.empty() && s.temperature.size() != n) ||
      (!s.sensed.empty() && s.sensed.size() != n) ||
      (!s.response.empty() && s.response.size() != n) || !(s.sample_time > 0.0)) {
    throw std::invalid_argument("fit_correction: signals of mismatched size or no sample time");
  }
  if (std::none_of(fit_rows.begin(), fit_rows.end(), [](bool b) { return b; })) {
    throw std::invalid_argument("fit_correction: no fitting rows");
  }
}

// The shares of the modes and of the direct path (kSecondMode) are fractions of the strain:
// each, and the first mode's 1 - a - b, in [0, 1]. A setting whose least squares leave that
// range is not taken (two modes at one frequency with shares 1.9 and -0.93 are one mode's shape
// refitted; a "mode" at 35 Hz with damping 1.06 and share -0.02 is a lag of something else).
bool shares_are_fractions(const Columns& columns, const ChannelCorrection& filters,
                          const Solved& solved) {
  if (!columns.mode_shares || !(filters.dynamics_frequency_hz > 0.0)) return true;
  const auto p = static_cast<Eigen::Index>(columns.phi.size());
  const bool second = filters.dynamics2_frequency_hz > 0.0;
  if (solved.coefficients.size() != p + (second ? 2 : 1)) return true;  // refused later
  const double a = solved.coefficients[p];
  const double b = second ? solved.coefficients[p + 1] : 0.0;
  const auto fraction = [](double v) { return v >= 0.0 && v <= 1.0; };
  return fraction(a) && fraction(b) && fraction(1.0 - a - b);
}

// The correction of solved coefficients (throws when the model's output would enter inverted).
ChannelCorrection correction_of(const CorrectionSignals& s, std::span<const CorrectionTerm> terms,
                                const Columns& columns, const Solved& solved,
                                const ChannelCorrection& filters) {
  const bool shares = columns.mode_shares && filters.dynamics_frequency_hz > 0.0;
  const bool second = shares && filters.dynamics2_frequency_hz > 0.0;
  const auto p = static_cast<Eigen::Index>(columns.phi.size());
  if (solved.coefficients.size() != p + (shares ? 1 : 0) + (second ? 1 : 0)) {
    throw std::invalid_argument("fit_correction: no finite fit (non-finite signals?)");
  }
  ChannelCorrection c = filters;
  c.temperature_reference_degc = s.temperature_reference_degc;
  apply_coefficients(terms, columns, solved.coefficients.head(p), c);
  if (shares) c.dynamics_direct = solved.coefficients[p];
  if (second) c.dynamics2_share = solved.coefficients[p + 1];
  if (!(1.0 + c.gain > 0.0)) {
    // The model's output would enter inverted (or not at all): not a correction of it.
    throw std::invalid_argument("fit_correction: the fit needs 1 + gain <= 0");
  }
  return c;
}

}  // namespace

std::vector<double> apply_correction(const CorrectionSignals& s,
                                     const models::ChannelCorrection& correction) {
  CorrectionStage stage(correction, s.sample_time);
  std::vector<double> out(s.y.size());
  for (std::size_t k = 0; k < s.y.size(); ++k) {
    out[k] = stage.step({s.y[k], s.drive.empty() ? 0.0 : s.drive[k], at(s.stress, k, 0.0),
                         at(s.temperature, k, correction.temperature_reference_degc),
                         at(s.sensed, k, 0.0), at(s.response, k, s.y[k])});
  }
  return out;
}

CorrectionFit fit_correction(const CorrectionSignals& s, std::span<const CorrectionTerm> terms,
                             const models::ChannelCorrection& start,
                             const std::vector<bool>& fit_rows) {
  check_signals(s, fit_rows);
  const std::size_t n = s.y.size();
  const Columns columns = make_columns(s, terms);
  const std::vector<bool> solved_rows = least_squares_rows(fit_rows);
  Solved best;
  ChannelCorrection best_filters;
  Regressors work;  // the columns of each setting tried, in buffers allocated once
  const auto evaluate = [&](const ChannelCorrection& filters) {
    fill_regressors(s, columns, filters, work);
    Solved solved = solve(work.target, work.columns, solved_rows);
    if (!shares_are_fractions(columns, filters, solved)) return false;
    if (solved.sse < best.sse) {
      best = std::move(solved);
      best_filters = filters;
      return true;
    }
    return false;
  };
  const std::vector<ChannelCorrection> grid = filter_grid(s, terms, start);
  for (const ChannelCorrection& filters : grid) {
    try {
      evaluate(filters);
    } catch (const std::invalid_argument&) {
      // a grid point the sample time cannot run (a delay or resonance too large): skipped
    }
  }
  refine(s, terms, start, best_filters, evaluate);
  // The first mode as chosen, or as given where its direct share alone left [0, 1].
  const ChannelCorrection first =
      std::isfinite(best.sse) || grid.size() != 1 ? best_filters : grid.front();
  if (has_term(terms, CorrectionTerm::kSecondMode) && start.dynamics2_frequency_hz == 0.0 &&
      first.dynamics_frequency_hz > 0.0) {
    // The second mode beside the first, then refined (with the first where it was searched).
    for (const ChannelCorrection& filters : second_mode_grid(s, first)) {
      try {
        evaluate(filters);
      } catch (const std::invalid_argument&) {
        // above what the sample time allows: skipped
      }
    }
    if (best_filters.dynamics2_frequency_hz > 0.0) refine(s, terms, start, best_filters, evaluate);
  }
  CorrectionFit fit;
  fit.correction = correction_of(s, terms, columns, best, best_filters);
  fit.output = apply_correction(s, fit.correction);
  for (std::size_t k = 0; k < n; ++k) {
    if (!fit_rows[k]) continue;
    const double e = s.recorded[k] - fit.output[k];
    fit.fit_sse += e * e;
  }
  return fit;
}

std::vector<std::vector<double>> held_out_outputs(const CorrectionSignals& s,
                                                  std::span<const CorrectionTerm> terms,
                                                  const models::ChannelCorrection& start,
                                                  const std::vector<bool>& fit_rows,
                                                  std::span<const int> fold, std::size_t folds) {
  check_signals(s, fit_rows);
  const std::size_t n = s.y.size();
  if (fold.size() != n) throw std::invalid_argument("held_out_outputs: a fold per sample");
  const std::vector<ChannelCorrection> grid = filter_grid(s, terms, start);
  if (grid.size() != 1) {
    throw std::invalid_argument("held_out_outputs: the filters must be chosen (in start)");
  }
  const Columns columns = make_columns(s, terms);
  const Regressors r = regressors(s, columns, grid.front());
  const auto p = static_cast<Eigen::Index>(r.columns.size());
  // One pass over the samples: the normal equations of every fitting row, and of each fold's.
  Normal all = zero_normal(p);
  std::vector<Normal> of_fold(folds, zero_normal(p));
  Eigen::VectorXd row(p);
  const std::vector<bool> solved_rows = least_squares_rows(fit_rows);
  for (std::size_t k = 0; k < n; ++k) {
    if (!solved_rows[k]) continue;
    const int f = fold[k];
    if (f >= 0 && static_cast<std::size_t>(f) < folds) {
      accumulate(of_fold[static_cast<std::size_t>(f)], r.target, r.columns, k, row);
    } else {
      accumulate(all, r.target, r.columns, k, row);
    }
  }
  std::vector<std::vector<double>> out;
  out.reserve(folds);
  for (std::size_t f = 0; f < folds; ++f) {
    Normal without = all;
    for (std::size_t g = 0; g < folds; ++g) {
      if (g == f) continue;
      without.g += of_fold[g].g;
      without.b += of_fold[g].b;
      without.energy += of_fold[g].energy;
    }
    const Solved solved = solve_normal(std::move(without));
    static_cast<void>(correction_of(s, terms, columns, solved, grid.front()));  // checks the fit
    // out = F[y] + sum_i c_i F[phi_i], with F[y] = recorded - target.
    std::vector<double> output(n);
    for (std::size_t k = 0; k < n; ++k) {
      double sum = s.recorded[k] - r.target[k];
      for (Eigen::Index i = 0; i < p; ++i)
        sum += solved.coefficients[i] * r.columns[static_cast<std::size_t>(i)][k];
      output[k] = sum;
    }
    out.push_back(std::move(output));
  }
  return out;
}

}  // namespace selfsense::identification
