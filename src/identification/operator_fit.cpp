#include "selfsense/identification/operator_fit.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "selfsense/identification/nnls.hpp"
#include "selfsense/identification/regressors.hpp"
#include "selfsense/identification/remanent_state.hpp"
#include "selfsense/operators/linear_creep.hpp"

namespace selfsense::identification {
namespace {

using operators::DeadZoneSuperposition;
using RowBlock = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

constexpr Eigen::Index kBlockRows = 512;
constexpr double kShapeSlopeFloor = 1e-2;  // relative slope of a superposition on any interval

// Which coefficients are bounded below, and by what; built group by group in column order.
struct Bounds {
  std::vector<bool> bounded{};
  std::vector<double> lower{};

  void add(std::size_t count, bool is_bounded, double bound) {
    bounded.insert(bounded.end(), count, is_bounded);
    lower.insert(lower.end(), count, bound);
  }
  [[nodiscard]] Eigen::Index size() const { return static_cast<Eigen::Index>(bounded.size()); }
};

BoundedLeastSquaresSolution solve(const GramAccumulator& acc, const Bounds& bounds) {
  return solve_bounded_least_squares(
      {acc.gram(), acc.moment(), acc.output_energy(), bounds.bounded,
       Eigen::Map<const Eigen::VectorXd>(bounds.lower.data(), bounds.size())});
}

// Which samples are rows of the normal equations: every `step`-th (k % step == 0, so ranges
// accumulated apart agree), each weighted by sqrt(step) so that the sums keep the units of
// every sample (OperatorStructure::row_step).
struct RowStep {
  std::size_t step{1};
  [[nodiscard]] bool keeps(std::size_t k) const { return k % step == 0; }
  [[nodiscard]] std::size_t next_kept(std::size_t k) const { return (k + step - 1) / step * step; }
  [[nodiscard]] double weight() const { return std::sqrt(static_cast<double>(step)); }
};

// Streams rows over the kept samples of [from, count) (the operator's state still follows every
// sample from 0, RegressorStream::skip between rows): fill(k, phi, row, target) writes one row,
// given the operator columns phi of sample k.
template <typename Fill>
GramAccumulator accumulate(const OperatorBasis& basis, std::span<const double> x,
                           std::span<const double> history, std::size_t count, Eigen::Index cols,
                           RowStep rows, Fill fill, std::size_t from = 0) {
  GramAccumulator acc(cols);
  RegressorStream stream(basis, history);
  RowBlock block(kBlockRows, cols);
  Eigen::VectorXd target(kBlockRows);
  Eigen::Index row = 0;
  const double weight = rows.weight();
  stream.skip(x.first(std::min(from, count)));
  for (std::size_t k = std::min(from, count); k < count; ++k) {
    const std::size_t kept = rows.next_kept(k);  // the samples before it only advance the state
    if (kept > k) {
      stream.skip(x.subspan(k, std::min(kept, count) - k));
      k = kept;
      if (k >= count) break;
    }
    const std::span<const double> phi = stream.next(x[k]);
    fill(k, phi, std::span<double>(block.row(row).data(), static_cast<std::size_t>(cols)),
         target(row));
    if (rows.step > 1) {
      block.row(row) *= weight;
      target(row) *= weight;
    }
    if (++row == kBlockRows) {
      acc.add(block, target);
      row = 0;
    }
  }
  if (row > 0) acc.add(block.topRows(row), target.head(row));
  return acc;
}

// The fit in progress: y = S[theta . phi] + sum_k g_k u_k + offset.
struct Fit {
  Eigen::VectorXd theta{};  // W_i, then c_rj
  DeadZoneSuperposition::Params shape{};
  std::vector<double> gains{};
  double offset{0.0};
  double rss{std::numeric_limits<double>::infinity()};  // output error on the fitted samples
  // v = theta . phi over the fitted samples, kept by the fitter that scored this fit (empty
  // when not yet computed): a refit of S alone needs no operator pass, and the refit of theta
  // after it starts from it.
  std::vector<double> inner{};
};

class Fitter {
 public:
  Fitter(const OperatorSignals& s, const OperatorBasis& basis, double weight_floor, bool offset,
         RowStep rows)
      : s_(s), basis_(basis), floor_(weight_floor), offset_(offset), rows_(rows) {}

  [[nodiscard]] std::size_t extras() const { return s_.linear_inputs.size() + (offset_ ? 1 : 0); }

  // Everything linear, S = identity. Returns the fit and its residual sum of squares.
  [[nodiscard]] Fit linear(std::span<const double> history, std::size_t count) const {
    return solve_linear(linear_gram(history, 0, count));
  }

  // Normal equations of the linear stage over samples [from, to).
  [[nodiscard]] GramAccumulator linear_gram(std::span<const double> history, std::size_t from,
                                            std::size_t to) const {
    const std::size_t ops = basis_.columns();
    const auto cols = static_cast<Eigen::Index>(ops + extras());
    return accumulate(
        basis_, s_.input, history, to, cols, rows_,
        [&](std::size_t k, auto phi, auto row, double& y) {
          std::copy(phi.begin(), phi.end(), row.begin());
          fill_extras(k, row.subspan(ops), 1.0);
          y = s_.output[k];
        },
        from);
  }

  [[nodiscard]] Fit solve_linear(const GramAccumulator& acc) const {
    const std::size_t ops = basis_.columns();
    const BoundedLeastSquaresSolution sol = solve(acc, operator_bounds(true));
    Fit fit;
    fit.theta = sol.theta.head(static_cast<Eigen::Index>(ops));
    unpack_extras(sol.theta, ops, fit);
    fit.rss = sol.residual_sum_of_squares;
    return fit;
  }

  // Kuhnen's equation error: S'[y - g u - offset] = theta . phi with S' = S^-1 in the slope
  // basis, its slope around 0 fixed at 1; g and offset kept from `from`.
  [[nodiscard]] Fit equation_error(const Fit& from, std::size_t per_side) const {
    const std::vector<double> inner = unloaded(from);
    const DeadZoneBasis dz = spread_dead_zones(inner, per_side);
    const std::size_t ops = basis_.columns();
    const std::size_t shape_cols = dz.columns() - 1;
    std::vector<double> b(dz.columns());
    const GramAccumulator acc = accumulate(basis_, s_.input, history_, inner.size(),
                                           static_cast<Eigen::Index>(ops + shape_cols), rows_,
                                           [&](std::size_t k, auto phi, auto row, double& y) {
                                             std::copy(phi.begin(), phi.end(), row.begin());
                                             dz.evaluate(inner[k], b);
                                             for (std::size_t j = 0; j < shape_cols; ++j)
                                               row[ops + j] = -b[1 + j];
                                             y = b[0];
                                           });
    Bounds bounds = operator_bounds(false);
    bounds.add(shape_cols, true, kShapeSlopeFloor);
    const BoundedLeastSquaresSolution sol = solve(acc, bounds);
    std::vector<double> slopes{1.0};
    for (std::size_t j = 0; j < shape_cols; ++j)
      slopes.push_back(sol.theta(static_cast<Eigen::Index>(ops + j)));
    Fit fit = from;
    fit.theta = sol.theta.head(static_cast<Eigen::Index>(ops));
    fit.shape = DeadZoneSuperposition(dz.superposition(slopes)).inverse().params();
    score(fit);
    return fit;
  }

  // Output error for S, g and offset with theta fixed (linear in them given v = theta . phi).
  [[nodiscard]] Fit refit_shape(const Fit& from) const {
    std::vector<double> inner = inner_of(from);
    DeadZoneBasis dz{from.shape.upper_thresholds, from.shape.lower_thresholds};
    const std::size_t shape_cols = dz.columns();
    const auto cols = static_cast<Eigen::Index>(shape_cols + extras());
    GramAccumulator acc(cols);
    RowBlock block(kBlockRows, cols);
    Eigen::VectorXd target(kBlockRows);
    Eigen::Index row = 0;
    const double weight = rows_.weight();
    for (std::size_t k = 0; k < inner.size(); ++k) {
      if (!rows_.keeps(k)) continue;
      const std::span<double> r(block.row(row).data(), static_cast<std::size_t>(cols));
      dz.evaluate(inner[k], r.first(shape_cols));
      fill_extras(k, r.subspan(shape_cols), 1.0);
      target(row) = s_.output[k];
      if (rows_.step > 1) {
        block.row(row) *= weight;
        target(row) *= weight;
      }
      if (++row == kBlockRows) {
        acc.add(block, target);
        row = 0;
      }
    }
    if (row > 0) acc.add(block.topRows(row), target.head(row));
    Bounds bounds;
    const double slope_scale = std::abs(from.shape.linear_weight);
    bounds.add(shape_cols, true, kShapeSlopeFloor * slope_scale);
    bounds.add(extras(), false, 0.0);
    const BoundedLeastSquaresSolution sol = solve(acc, bounds);
    Fit fit = from;
    std::vector<double> slopes(sol.theta.data(), sol.theta.data() + shape_cols);
    fit.shape = dz.superposition(slopes);
    unpack_extras(sol.theta, shape_cols, fit);
    fit.inner = std::move(inner);  // theta unchanged
    fit.rss = output_rss(fit, fit.inner);
    return fit;
  }

  // Gauss-Newton step for theta, g and offset with S fixed: S is piecewise linear, so around
  // v0 = theta0 . phi, S(v) = S(v0) + S'(v0) (v - v0) exactly while v stays on its segment.
  [[nodiscard]] Fit refit_operator(const Fit& from) const {
    const DeadZoneSuperposition shape(from.shape);
    const std::vector<double> v0 = inner_of(from);
    const std::size_t ops = basis_.columns();
    const auto cols = static_cast<Eigen::Index>(ops + extras());
    const GramAccumulator acc =
        accumulate(basis_, s_.input, history_, v0.size(), cols, rows_,
                   [&](std::size_t k, auto phi, auto row, double& y) {
                     const double slope = shape.slope(v0[k]);
                     for (std::size_t i = 0; i < ops; ++i)
                       row[i] = slope * phi[i];
                     fill_extras(k, row.subspan(ops), 1.0);
                     y = s_.output[k] - (shape.evaluate(v0[k]) - slope * v0[k]);
                   });
    const BoundedLeastSquaresSolution sol = solve(acc, operator_bounds(true));
    Fit fit = from;
    fit.theta = sol.theta.head(static_cast<Eigen::Index>(ops));
    unpack_extras(sol.theta, ops, fit);
    score(fit);
    return fit;
  }

  void set_history(std::vector<double> history) { history_ = std::move(history); }

 private:
  // Bounds of the operator columns: W_i >= floor, c_rj >= 0, then (optionally) free extras.
  [[nodiscard]] Bounds operator_bounds(bool with_extras) const {
    Bounds b;
    b.add(basis_.plays(), true, floor_);
    b.add(basis_.creep(), true, 0.0);
    b.add(basis_.hinges(), false, 0.0);
    if (with_extras) b.add(extras(), false, 0.0);
    return b;
  }

  void fill_extras(std::size_t k, std::span<double> out, double one) const {
    std::size_t c = 0;
    for (const auto& u : s_.linear_inputs)
      out[c++] = u[k];
    if (offset_) out[c] = one;
  }

  void unpack_extras(const Eigen::VectorXd& theta, std::size_t first, Fit& fit) const {
    auto c = static_cast<Eigen::Index>(first);
    fit.gains.clear();
    for (std::size_t u = 0; u < s_.linear_inputs.size(); ++u)
      fit.gains.push_back(theta(c++));
    fit.offset = offset_ ? theta(c) : 0.0;
  }

  // y - g u - offset.
  [[nodiscard]] std::vector<double> unloaded(const Fit& fit) const {
    std::vector<double> out(s_.output.begin(), s_.output.end());
    for (std::size_t k = 0; k < out.size(); ++k) {
      out[k] -= fit.offset;
      for (std::size_t u = 0; u < fit.gains.size(); ++u)
        out[k] -= fit.gains[u] * s_.linear_inputs[u][k];
    }
    return out;
  }

  // v = theta . phi over the fitted samples.
  [[nodiscard]] std::vector<double> unloaded_inner(const Fit& fit) const {
    RegressorStream stream(basis_, history_);
    std::vector<double> v(s_.output.size());
    for (std::size_t k = 0; k < v.size(); ++k) {
      const std::span<const double> phi = stream.next(s_.input[k]);
      v[k] = Eigen::Map<const Eigen::VectorXd>(phi.data(), static_cast<Eigen::Index>(phi.size()))
                 .dot(fit.theta);
    }
    return v;
  }

  // fit.inner when this fitter computed it, else v of fit's theta afresh.
  [[nodiscard]] std::vector<double> inner_of(const Fit& fit) const {
    return fit.inner.empty() ? unloaded_inner(fit) : fit.inner;
  }

  // v of fit's theta, and the output error through its S.
  void score(Fit& fit) const {
    fit.inner = unloaded_inner(fit);
    fit.rss = output_rss(fit, fit.inner);
  }

  [[nodiscard]] double output_rss(const Fit& fit, std::span<const double> v) const {
    const DeadZoneSuperposition shape(fit.shape);
    double rss = 0.0;
    for (std::size_t k = 0; k < v.size(); ++k) {
      double y = shape.evaluate(v[k]) + fit.offset;
      for (std::size_t u = 0; u < fit.gains.size(); ++u)
        y += fit.gains[u] * s_.linear_inputs[u][k];
      rss += (s_.output[k] - y) * (s_.output[k] - y);
    }
    return rss;
  }

  const OperatorSignals& s_;
  const OperatorBasis& basis_;
  double floor_;
  bool offset_;
  RowStep rows_;
  std::vector<double> history_{};
};

void check_signals(const OperatorSignals& s) {
  const std::size_t n = s.input.size();
  if (n < 2 || s.output.size() != n) {
    throw std::invalid_argument("fit_operator: input and output need the same length >= 2");
  }
  for (std::size_t u = 0; u < s.linear_inputs.size(); ++u) {
    if (s.linear_inputs[u].size() != n) {
      throw std::invalid_argument("fit_operator: linear input " + std::to_string(u) +
                                  " has a different length");
    }
  }
  if (!(s.sample_time > 0.0)) throw std::invalid_argument("fit_operator: sample time must be > 0");
  const auto [lo, hi] = std::minmax_element(s.input.begin(), s.input.end());
  if (!(*hi > *lo)) throw std::invalid_argument("fit_operator: the input is constant");
}

OperatorBasis basis_for(const OperatorSignals& signals, const OperatorStructure& structure,
                        double x_range) {
  const double ts = signals.sample_time;
  OperatorBasis basis;
  basis.thresholds.push_back(0.0);
  for (std::size_t i = 1; i <= structure.plays; ++i) {
    basis.thresholds.push_back(0.5 * x_range * static_cast<double>(i) /
                               static_cast<double>(structure.plays + 1));
  }
  if (structure.eigenvalues > 0) {
    const double duration = ts * static_cast<double>(signals.input.size());
    const double fastest =
        structure.fastest_eigenvalue > 0 ? structure.fastest_eigenvalue : std::min(100.0, 0.1 / ts);
    const double slowest = structure.slowest_eigenvalue > 0
                               ? structure.slowest_eigenvalue
                               : std::min(3.0 / duration, 0.5 * fastest);
    basis.eigenvalues = operators::log_spaced_eigenvalues(fastest, slowest, structure.eigenvalues);
    for (const double l : basis.eigenvalues)
      basis.gains.push_back(-std::expm1(-l * ts));
    basis.creep_rows.push_back(0);
    const std::size_t extra = std::min(structure.creep_plays, structure.plays);
    for (std::size_t k = 1; k <= extra; ++k) {
      basis.creep_rows.push_back(k * (structure.plays + 1) / (extra + 1));
    }
  }
  // After a full sweep the play of threshold r moves within [lo + r, hi - r]: the hinges
  // split that span evenly (plays that hardly move get none).
  const double x_lo = *std::min_element(signals.input.begin(), signals.input.end());
  for (std::size_t i = 0; i < basis.thresholds.size() && structure.bias_levels > 0; ++i) {
    const double r = basis.thresholds[i];
    const double span = x_range - 2.0 * r;
    if (span < 0.1 * x_range) continue;
    for (std::size_t k = 1; k <= structure.bias_levels; ++k) {
      basis.hinge_rows.push_back(i);
      basis.hinge_levels.push_back(x_lo + r +
                                   span * static_cast<double>(k) /
                                       static_cast<double>(structure.bias_levels + 1));
    }
  }
  return basis;
}

// Remanent state: the candidate history that best explains the first part of `signals` with
// the operator `basis` (linear stage, S = identity); the two best grid candidates are refined
// (rising and falling starts can be close). creep_lags: score with the creep lags of the
// linear term, or with the plays alone.
std::vector<double> estimate_history(const OperatorSignals& signals, const OperatorBasis& basis,
                                     double weight_floor, bool offset, RowStep rows,
                                     bool creep_lags) {
  const std::size_t n = signals.input.size();
  const auto [x_lo, x_hi] = std::minmax_element(signals.input.begin(), signals.input.end());
  // The start state matters until the input has swept its whole range (wiping-out), so
  // twice that span decides between candidates.
  const std::size_t sweep = std::min(n, sweep_length(signals.input));
  const std::size_t head = std::min(n, std::max<std::size_t>(2 * sweep, 2000));
  // The other creep columns cost most of the normal equations and say little about where the
  // plays started. After the sweep every candidate's plays are wiped to the same state, so the
  // rows of [sweep, head) are accumulated once; the lags still remember the start there, which
  // the shared rows ignore (it only blurs the score).
  OperatorBasis scoring = basis;
  scoring.hinge_rows.clear();  // the start shows in the plays; hinges only refine their output
  scoring.hinge_levels.clear();
  if (!creep_lags) {
    scoring.creep_rows.clear();
  } else if (scoring.creep_rows.size() > 1) {
    scoring.creep_rows.erase(scoring.creep_rows.begin() + 1, scoring.creep_rows.end());
  }
  const Fitter scorer(signals, scoring, weight_floor, offset, rows);
  const GramAccumulator shared = scorer.linear_gram({&signals.input.front(), 1}, sweep, head);
  const auto residual = [&](const std::vector<double>& h) {
    GramAccumulator acc = scorer.linear_gram(h, 0, sweep);
    acc.add(shared);
    return scorer.solve_linear(acc).rss;
  };
  std::vector<std::pair<double, std::vector<double>>> ranked;
  for (std::vector<double>& candidate : history_candidates(signals.input)) {
    ranked.emplace_back(residual(candidate), std::move(candidate));
  }
  std::sort(ranked.begin(), ranked.end(),
            [](const auto& l, const auto& r) { return l.first < r.first; });
  std::vector<double> history{signals.input.front()};
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < std::min<std::size_t>(2, ranked.size()); ++i) {
    std::vector<double> candidate = ranked[i].second;
    double rss = ranked[i].first;
    if (candidate.size() > 1) {
      std::vector<double> refined =
          refine_turning_point(candidate, (*x_hi - *x_lo) / 8.0, residual);
      const double refined_rss = residual(refined);
      if (refined_rss < rss) {
        rss = refined_rss;
        candidate = std::move(refined);
      }
    }
    if (rss < best) {
      best = rss;
      history = std::move(candidate);
    }
  }
  return history;
}

// Candidate starts for best_start: `first` (when given, it wins ties), the picks of the
// searches that rank the candidates within the recorded range with cheap proxies of the basis
// (the plays alone, or with the creep lags of the linear term; no hinges), the demagnetised
// start and the starts from beyond the recorded range. On the simulated transducer, which
// starts from negative saturation, the proxies picked a start inside the range (a different
// one for 24 and 48 plays, so 48 fitted worse) and the new recording's T_hat was 1.03 %; the
// whole basis picks a turning point below the range: 0.42 % (docs/identification.md).
std::vector<std::vector<double>> start_finalists(const OperatorSignals& signals,
                                                 const OperatorBasis& basis, double weight_floor,
                                                 bool offset, RowStep rows,
                                                 const std::vector<double>& first) {
  std::vector<std::vector<double>> finalists;
  if (!first.empty()) finalists.push_back(first);
  finalists.push_back(estimate_history(signals, basis, weight_floor, offset, rows, true));
  if (basis.creep() > 0)
    finalists.push_back(estimate_history(signals, basis, weight_floor, offset, rows, false));
  finalists.push_back({signals.input.front()});
  for (std::vector<double>& c : outside_candidates(signals.input))
    finalists.push_back(std::move(c));
  return finalists;
}

// The finalist whose linear stage (the whole basis, S = identity) fits the whole recording
// best, its last turning point then refined by the same score. Rows after the first sweep are
// the same for every history (the plays are wiped; the creep lags still remember, which the
// shared rows ignore), so they are accumulated once.
std::vector<double> best_start(const Fitter& fitter, std::span<const double> x,
                               const std::vector<std::vector<double>>& finalists) {
  const std::size_t n = x.size();
  const std::size_t sweep = std::min(n, sweep_length(x));
  const GramAccumulator shared = fitter.linear_gram(finalists.front(), sweep, n);
  const auto residual = [&](const std::vector<double>& h) {
    GramAccumulator acc = fitter.linear_gram(h, 0, sweep);
    acc.add(shared);
    return fitter.solve_linear(acc).rss;
  };
  double best = std::numeric_limits<double>::infinity();
  std::vector<double> chosen = finalists.front();
  for (const std::vector<double>& h : finalists) {
    const double rss = residual(h);
    if (rss < best) {
      best = rss;
      chosen = h;
    }
  }
  if (chosen.size() > 1) {
    const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
    std::vector<double> refined = refine_turning_point(chosen, (*hi - *lo) / 8.0, residual);
    if (residual(refined) < best) chosen = std::move(refined);
  }
  return chosen;
}

// Linear stage, then (with dead zones) the equation error for S and output-error passes that
// refit S and the operator in turn, keeping whichever fit explains the data best.
Fit fit_with_history(Fitter& fitter, const std::vector<double>& history,
                     const OperatorStructure& structure, std::size_t n) {
  fitter.set_history(history);
  Fit best = fitter.linear(history, n);
  if (structure.dead_zones == 0) return best;
  // S = identity is a superposition too: the linear stage competes, so dead zones can never
  // make the fit on these data worse than the structure without them.
  Fit candidate = fitter.equation_error(best, structure.dead_zones);
  if (candidate.rss < best.rss) best = candidate;
  for (std::size_t pass = 0; pass < structure.refinement_passes; ++pass) {
    candidate = fitter.refit_shape(candidate);
    if (candidate.rss < best.rss) best = candidate;
    candidate = fitter.refit_operator(candidate);
    if (candidate.rss < best.rss) best = candidate;
  }
  return best;
}

// v = S^-1[y - g u - offset]: the output seen through the fitted superposition, on which the
// operator is linear again.
std::vector<double> inner_output(const OperatorSignals& signals, const Fit& fit) {
  const DeadZoneSuperposition inverse = DeadZoneSuperposition(fit.shape).inverse();
  std::vector<double> v(signals.output.size());
  for (std::size_t k = 0; k < v.size(); ++k) {
    double y = signals.output[k] - fit.offset;
    for (std::size_t u = 0; u < fit.gains.size(); ++u)
      y -= fit.gains[u] * signals.linear_inputs[u][k];
    v[k] = inverse.evaluate(y);
  }
  return v;
}

}  // namespace

OperatorModel fit_operator(const OperatorSignals& signals, const OperatorStructure& structure) {
  check_signals(signals);
  const std::size_t n = signals.input.size();
  const auto [x_lo, x_hi] = std::minmax_element(signals.input.begin(), signals.input.end());
  const auto [y_lo, y_hi] = std::minmax_element(signals.output.begin(), signals.output.end());
  const double x_range = *x_hi - *x_lo;
  const double y_range = std::max(*y_hi - *y_lo, std::numeric_limits<double>::min());
  // W_i >= floor keeps the PI invertible with margin far below any useful weight.
  const double weight_floor = 1e-6 * y_range / x_range;
  const OperatorBasis basis = basis_for(signals, structure, x_range);
  const RowStep rows{std::max<std::size_t>(1, structure.row_step)};
  Fitter fitter(signals, basis, weight_floor, structure.fit_offset, rows);

  const bool search = structure.estimate_history && structure.plays > 0 && structure.start.empty();
  std::vector<double> history{signals.input.front()};
  if (!structure.start.empty()) history = structure.start;
  if (search) {
    const RowStep scored{ranking_row_step(rows.step)};
    const Fitter start_fitter(signals, basis, weight_floor, structure.fit_offset, scored);
    history =
        best_start(start_fitter, signals.input,
                   start_finalists(signals, basis, weight_floor, structure.fit_offset, scored, {}));
  }
  Fit fit = fit_with_history(fitter, history, structure, n);
  if (basis.hinges() > 0 && structure.dead_zones > 0) {
    // The dead-zone stage is not convex: the equation-error start with hinges can land in a
    // worse optimum than the fit without them. That fit, with zero hinge weights, is in this
    // class; refined from there it competes, so hinges never fit the data worse.
    OperatorBasis plain = basis;
    plain.hinge_rows.clear();
    plain.hinge_levels.clear();
    Fitter plain_fitter(signals, plain, weight_floor, structure.fit_offset, rows);
    Fit candidate = fit_with_history(plain_fitter, history, structure, n);
    candidate.theta.conservativeResize(static_cast<Eigen::Index>(basis.columns()));
    candidate.theta.tail(static_cast<Eigen::Index>(basis.hinges())).setZero();
    candidate.inner.clear();  // the hinges' zeros change the dot product's rounding
    if (candidate.rss < fit.rss) fit = candidate;
    for (std::size_t pass = 0; pass < structure.refinement_passes; ++pass) {
      candidate = fitter.refit_operator(candidate);
      if (candidate.rss < fit.rss) fit = candidate;
      candidate = fitter.refit_shape(candidate);
      if (candidate.rss < fit.rss) fit = candidate;
    }
  }
  if (search && structure.dead_zones > 0 && DeadZoneSuperposition(fit.shape).size() > 0) {
    // The first search scored the start with S = identity; when the data need dead zones its
    // model error outweighs the start's signature and a richer basis could pick a worse start
    // (and fit worse than a smaller one). Search again through the fitted S, where the
    // operator is linear, and keep the better fit.
    const std::vector<double> v = inner_output(signals, fit);
    const OperatorSignals inner{signals.input, {}, v, signals.sample_time};
    const RowStep scored{ranking_row_step(rows.step)};
    const Fitter inner_fitter(inner, basis, weight_floor, true, scored);
    std::vector<double> second =
        best_start(inner_fitter, signals.input,
                   start_finalists(inner, basis, weight_floor, true, scored, history));
    if (second != history) {
      Fit refit = fit_with_history(fitter, second, structure, n);
      if (refit.rss < fit.rss) {
        fit = std::move(refit);
        history = std::move(second);
      }
    }
  }

  OperatorModel model;
  model.sample_time = signals.sample_time;
  model.history = history;
  model.linear_gains = fit.gains;
  model.offset = fit.offset;
  model.op.superposition = fit.shape;
  auto& h = model.op.hysteresis;
  h.linear_weight = fit.theta(0);
  for (std::size_t i = 1; i < basis.plays(); ++i) {
    const auto c = static_cast<Eigen::Index>(i);
    h.thresholds.push_back(basis.thresholds[i]);
    h.weights.push_back(fit.theta(c) - fit.theta(c - 1));
  }
  auto& creep = model.op.creep;
  creep.eigenvalues = basis.eigenvalues;
  for (const std::size_t r : basis.creep_rows)
    creep.thresholds.push_back(basis.thresholds[r]);
  for (std::size_t c = 0; c < basis.creep(); ++c) {
    creep.weights.push_back(std::max(0.0, fit.theta(static_cast<Eigen::Index>(basis.plays() + c))));
  }
  auto& hinges = model.op.hinges;
  for (std::size_t g = 0; g < basis.hinges(); ++g) {
    hinges.thresholds.push_back(basis.thresholds[basis.hinge_rows[g]]);
    hinges.levels.push_back(basis.hinge_levels[g]);
    hinges.weights.push_back(
        fit.theta(static_cast<Eigen::Index>(basis.plays() + basis.creep() + g)));
  }
  return model;
}

void simulate_operator(const OperatorModel& model, std::span<const double> x,
                       const std::vector<std::span<const double>>& linear_inputs,
                       std::span<double> y) {
  operators::HysteresisCreep op(model.op, model.sample_time);
  op.set_history(model.history);
  for (std::size_t k = 0; k < x.size(); ++k) {
    double v = op.step(x[k]) + model.offset + model.quadratic * x[k] * x[k];
    for (std::size_t u = 0; u < linear_inputs.size(); ++u) {
      v += model.linear_gains[u] * linear_inputs[u][k];
    }
    y[k] = v;
  }
}

}  // namespace selfsense::identification
