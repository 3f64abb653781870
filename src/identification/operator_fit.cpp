#include "selfsense/identification/operator_fit.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "selfsense/identification/nnls.hpp"
#include "selfsense/operators/kernels.hpp"
#include "selfsense/operators/linear_creep.hpp"

namespace selfsense::identification {
namespace {

using operators::DeadZoneSuperposition;
using operators::HysteresisCreep;
using RowBlock = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

constexpr Eigen::Index kBlockRows = 512;

// Columns of the regression and how each row is produced.
struct Layout {
  std::vector<double> thresholds{};  // r_0 = 0 first; creep thresholds are a subset
  std::vector<std::size_t> creep_rows{};
  std::vector<double> eigenvalues{};
  std::vector<double> gains{};  // a_j = 1 - exp(-lambda_j Ts)
  std::vector<double> upper{};  // S' dead-zone thresholds on the inner signal (stage 2)
  std::vector<double> lower{};
  std::size_t linear_inputs{0};  // u_k columns (stage 1)
  bool offset{false};            // constant column (stage 1)

  [[nodiscard]] Eigen::Index plays() const { return static_cast<Eigen::Index>(thresholds.size()); }
  [[nodiscard]] Eigen::Index creep() const {
    return static_cast<Eigen::Index>(creep_rows.size() * eigenvalues.size());
  }
  [[nodiscard]] Eigen::Index dead_zones() const {
    return static_cast<Eigen::Index>(upper.size() + lower.size());
  }
  [[nodiscard]] Eigen::Index cols() const {
    return plays() + creep() + dead_zones() + static_cast<Eigen::Index>(linear_inputs) +
           (offset ? 1 : 0);
  }
};

// Streams the regression rows of samples [0, count) into a GramAccumulator.
//   stage 1: target y,  columns q_i (W_i), z_rj (c_rj), u_k (g_k), 1 (offset)
//   stage 2: target v - Zu_1(v) - Zl_1(v) with v = y - g u - offset,
//            columns q_i, z_rj, -(Z_j(v) - Z_{j+1}(v)) (G_j)
GramAccumulator accumulate(const Layout& layout, const OperatorSignals& s,
                           std::span<const double> inner, std::span<const double> history,
                           std::size_t count) {
  const Eigen::Index cols = layout.cols();
  GramAccumulator acc(cols);
  std::vector<double> plays(layout.thresholds.size(), history.front());
  for (const double h : history)
    operators::kernels::play_bank_step(h, layout.thresholds, plays);
  const std::size_t n_eig = layout.eigenvalues.size();
  std::vector<double> lags(layout.creep_rows.size() * n_eig);
  for (std::size_t i = 0; i < layout.creep_rows.size(); ++i) {
    std::fill_n(lags.begin() + static_cast<std::ptrdiff_t>(i * n_eig), n_eig,
                plays[layout.creep_rows[i]]);
  }
  RowBlock block(kBlockRows, cols);
  Eigen::VectorXd target(kBlockRows);
  Eigen::Index row = 0;
  const bool stage2 = layout.dead_zones() > 0;
  for (std::size_t k = 0; k < count; ++k) {
    operators::kernels::play_bank_step(s.input[k], layout.thresholds, plays);
    Eigen::Index c = 0;
    for (std::size_t i = 0; i < plays.size(); ++i) {
      block(row, c++) = plays[i] - (i + 1 < plays.size() ? plays[i + 1] : 0.0);
    }
    for (std::size_t i = 0; i < layout.creep_rows.size(); ++i) {
      const double p = plays[layout.creep_rows[i]];
      for (std::size_t j = 0; j < n_eig; ++j) {
        double& z = lags[i * n_eig + j];
        z += layout.gains[j] * (p - z);
        block(row, c++) = z;
      }
    }
    if (stage2) {
      const double v = inner[k];
      double y = v;
      const auto side = [&](const std::vector<double>& d, bool up) {
        for (std::size_t j = 0; j < d.size(); ++j) {
          const double zj = up ? std::max(v - d[j], 0.0) : std::min(v - d[j], 0.0);
          const double zn = j + 1 < d.size()
                                ? (up ? std::max(v - d[j + 1], 0.0) : std::min(v - d[j + 1], 0.0))
                                : 0.0;
          if (j == 0) y -= zj;
          block(row, c++) = -(zj - zn);
        }
      };
      side(layout.upper, true);
      side(layout.lower, false);
      target(row) = y;
    } else {
      for (std::size_t u = 0; u < layout.linear_inputs; ++u)
        block(row, c++) = s.linear_inputs[u][k];
      if (layout.offset) block(row, c++) = 1.0;
      target(row) = s.output[k];
    }
    if (++row == kBlockRows) {
      acc.add(block, target);
      row = 0;
    }
  }
  if (row > 0) acc.add(block.topRows(row), target.head(row));
  return acc;
}

struct Bounds {
  std::vector<bool> bounded{};
  Eigen::VectorXd lower{};
};

Bounds bounds_for(const Layout& layout, double weight_floor) {
  const Eigen::Index n = layout.cols();
  Bounds b{std::vector<bool>(static_cast<std::size_t>(n), false), Eigen::VectorXd::Zero(n)};
  Eigen::Index c = 0;
  for (Eigen::Index i = 0; i < layout.plays(); ++i, ++c) {
    b.bounded[static_cast<std::size_t>(c)] = true;
    b.lower(c) = weight_floor;
  }
  for (Eigen::Index i = 0; i < layout.creep(); ++i, ++c)
    b.bounded[static_cast<std::size_t>(c)] = true;
  for (Eigen::Index i = 0; i < layout.dead_zones(); ++i, ++c) {
    b.bounded[static_cast<std::size_t>(c)] = true;
    b.lower(c) = 1e-2;  // slope of S' at least 1 % of its initial slope
  }
  return b;
}

BoundedLeastSquaresSolution solve(const Layout& layout, const GramAccumulator& acc,
                                  double weight_floor) {
  const Bounds b = bounds_for(layout, weight_floor);
  return solve_bounded_least_squares(
      {acc.gram(), acc.moment(), acc.output_energy(), b.bounded, b.lower});
}

// Dead-zone thresholds on the inner signal, spread over its positive and negative range.
void place_dead_zones(Layout& layout, std::span<const double> inner, std::size_t per_side) {
  const auto [lo, hi] = std::minmax_element(inner.begin(), inner.end());
  const double span = *hi - *lo;
  for (std::size_t j = 1; j <= per_side; ++j) {
    const double f = static_cast<double>(j) / static_cast<double>(per_side + 1);
    if (*hi > 0.05 * span) layout.upper.push_back(f * *hi);
    if (*lo < -0.05 * span) layout.lower.push_back(f * *lo);
  }
}

// Samples until the input has come within 2 % of both its minimum and its maximum.
std::size_t sweep_length(std::span<const double> x) {
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  const double margin = 0.02 * (*hi - *lo);
  bool low = false;
  bool high = false;
  for (std::size_t k = 0; k < x.size(); ++k) {
    low = low || x[k] <= *lo + margin;
    high = high || x[k] >= *hi - margin;
    if (low && high) return k + 1;
  }
  return x.size();
}

// Candidate input histories before the first sample x0: demagnetised at x0, or on the major
// loop (rest at one extreme, then the other) with a last turning point a before x0.
std::vector<std::vector<double>> history_candidates(std::span<const double> x) {
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  const double x0 = x.front();
  std::vector<std::vector<double>> out{{x0}};
  constexpr int kLevels = 8;
  for (int i = 0; i <= kLevels; ++i) {
    const double a = *lo + (*hi - *lo) * i / kLevels;
    if (a < x0) out.push_back({*lo, *hi, a, x0});  // came down to a, now rising to x0
    if (a > x0) out.push_back({*hi, *lo, a, x0});  // went up to a, now falling to x0
  }
  return out;
}

// Golden-section search for the last turning point a = h[end - 2] within +-step, on the same
// side of the first sample x0 = h[end - 1] (the history must still turn there).
template <typename Residual>
std::vector<double> refine_turning_point(std::vector<double> h, double step, Residual residual) {
  const double x0 = h.back();
  double& turn = h[h.size() - 2];
  double a = turn - step;
  double b = turn + step;
  if (turn < x0) b = std::min(b, x0);
  if (turn > x0) a = std::max(a, x0);
  constexpr double kGolden = 0.6180339887498949;
  const auto at = [&](double v) {
    turn = v;
    return residual(h);
  };
  double c = b - kGolden * (b - a);
  double d = a + kGolden * (b - a);
  double fc = at(c);
  double fd = at(d);
  for (int i = 0; i < 10; ++i) {
    if (fc < fd) {
      b = d;
      d = c;
      fd = fc;
      c = b - kGolden * (b - a);
      fc = at(c);
    } else {
      a = c;
      c = d;
      fc = fd;
      d = a + kGolden * (b - a);
      fd = at(d);
    }
  }
  turn = fc < fd ? c : d;
  return h;
}

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

}  // namespace

OperatorModel fit_operator(const OperatorSignals& signals, const OperatorStructure& structure) {
  check_signals(signals);
  const std::size_t n = signals.input.size();
  const double ts = signals.sample_time;
  const auto [x_lo, x_hi] = std::minmax_element(signals.input.begin(), signals.input.end());
  const auto [y_lo, y_hi] = std::minmax_element(signals.output.begin(), signals.output.end());
  const double x_range = *x_hi - *x_lo;
  const double y_range = std::max(*y_hi - *y_lo, std::numeric_limits<double>::min());
  // W_i >= floor keeps the PI invertible with margin far below any useful weight.
  const double weight_floor = 1e-6 * y_range / x_range;

  Layout layout;
  layout.thresholds.push_back(0.0);
  for (std::size_t i = 1; i <= structure.plays; ++i) {
    layout.thresholds.push_back(0.5 * x_range * static_cast<double>(i) /
                                static_cast<double>(structure.plays + 1));
  }
  if (structure.eigenvalues > 0) {
    const double duration = ts * static_cast<double>(n);
    const double fastest =
        structure.fastest_eigenvalue > 0 ? structure.fastest_eigenvalue : std::min(100.0, 0.1 / ts);
    const double slowest = structure.slowest_eigenvalue > 0
                               ? structure.slowest_eigenvalue
                               : std::min(3.0 / duration, 0.5 * fastest);
    layout.eigenvalues = operators::log_spaced_eigenvalues(fastest, slowest, structure.eigenvalues);
    for (const double l : layout.eigenvalues)
      layout.gains.push_back(-std::expm1(-l * ts));
    layout.creep_rows.push_back(0);
    const std::size_t extra = std::min(structure.creep_plays, structure.plays);
    for (std::size_t k = 1; k <= extra; ++k) {
      layout.creep_rows.push_back(k * (structure.plays + 1) / (extra + 1));
    }
  }
  layout.linear_inputs = signals.linear_inputs.size();
  layout.offset = structure.fit_offset;

  // Remanent state: the candidate history that best explains the first part of the data, its
  // last turning point then refined by golden-section search between the grid neighbours.
  std::vector<double> history{signals.input.front()};
  if (structure.estimate_history && structure.plays > 0) {
    // The start state matters until the input has swept its whole range (wiping-out), so
    // twice that span decides between candidates.
    const std::size_t head =
        std::min(n, std::max<std::size_t>(2 * sweep_length(signals.input), 2000));
    const auto residual = [&](const std::vector<double>& candidate) {
      const GramAccumulator acc = accumulate(layout, signals, {}, candidate, head);
      return solve(layout, acc, weight_floor).residual_sum_of_squares;
    };
    // Grid first, then refine the two best grid candidates (rising and falling starts can
    // be close) and keep the best refined one.
    std::vector<std::pair<double, std::vector<double>>> ranked;
    for (std::vector<double>& candidate : history_candidates(signals.input)) {
      ranked.emplace_back(residual(candidate), std::move(candidate));
    }
    std::sort(ranked.begin(), ranked.end(),
              [](const auto& l, const auto& r) { return l.first < r.first; });
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < std::min<std::size_t>(2, ranked.size()); ++i) {
      std::vector<double> candidate = ranked[i].second;
      if (candidate.size() > 1)
        candidate = refine_turning_point(candidate, x_range / 8.0, residual);
      const double rss = std::min(residual(candidate), ranked[i].first);
      if (rss < best) {
        best = rss;
        history = rss < ranked[i].first ? candidate : ranked[i].second;
      }
    }
  }

  // Stage 1: everything linear with S = identity.
  const BoundedLeastSquaresSolution first =
      solve(layout, accumulate(layout, signals, {}, history, n), weight_floor);
  Eigen::VectorXd theta = first.theta;
  OperatorModel model;
  model.sample_time = ts;
  model.history = history;
  const Eigen::Index lin0 = layout.plays() + layout.creep();
  for (std::size_t u = 0; u < layout.linear_inputs; ++u) {
    model.linear_gains.push_back(theta(lin0 + static_cast<Eigen::Index>(u)));
  }
  model.offset = layout.offset ? theta(layout.cols() - 1) : 0.0;

  // Stage 2: inverse superposition on the equation error, g and offset kept.
  DeadZoneSuperposition::Params shape_inverse;
  if (structure.dead_zones > 0) {
    std::vector<double> inner(n);
    for (std::size_t k = 0; k < n; ++k) {
      double v = signals.output[k] - model.offset;
      for (std::size_t u = 0; u < layout.linear_inputs; ++u) {
        v -= model.linear_gains[u] * signals.linear_inputs[u][k];
      }
      inner[k] = v;
    }
    Layout shaped = layout;
    shaped.linear_inputs = 0;
    shaped.offset = false;
    place_dead_zones(shaped, inner, structure.dead_zones);
    if (shaped.dead_zones() > 0) {
      theta = solve(shaped, accumulate(shaped, signals, inner, history, n), weight_floor).theta;
      Eigen::Index c = shaped.plays() + shaped.creep();
      const auto side = [&](const std::vector<double>& d, std::vector<double>& thresholds,
                            std::vector<double>& weights) {
        double previous = 1.0;
        for (const double dj : d) {
          thresholds.push_back(dj);
          weights.push_back(theta(c) - previous);
          previous = theta(c++);
        }
      };
      side(shaped.upper, shape_inverse.upper_thresholds, shape_inverse.upper_weights);
      side(shaped.lower, shape_inverse.lower_thresholds, shape_inverse.lower_weights);
    }
  }

  // Partial sums back to PI weights; creep weights as they are.
  auto& h = model.op.hysteresis;
  h.linear_weight = theta(0);
  for (Eigen::Index i = 1; i < layout.plays(); ++i) {
    h.thresholds.push_back(layout.thresholds[static_cast<std::size_t>(i)]);
    h.weights.push_back(theta(i) - theta(i - 1));
  }
  auto& creep = model.op.creep;
  creep.eigenvalues = layout.eigenvalues;
  for (const std::size_t r : layout.creep_rows)
    creep.thresholds.push_back(layout.thresholds[r]);
  for (Eigen::Index c = 0; c < layout.creep(); ++c) {
    creep.weights.push_back(std::max(0.0, theta(layout.plays() + c)));
  }
  model.op.superposition = DeadZoneSuperposition(shape_inverse).inverse().params();
  return model;
}

void simulate_operator(const OperatorModel& model, std::span<const double> x,
                       const std::vector<std::span<const double>>& linear_inputs,
                       std::span<double> y) {
  HysteresisCreep op(model.op, model.sample_time);
  op.set_history(model.history);
  for (std::size_t k = 0; k < x.size(); ++k) {
    double v = op.step(x[k]) + model.offset;
    for (std::size_t u = 0; u < linear_inputs.size(); ++u)
      v += model.linear_gains[u] * linear_inputs[u][k];
    y[k] = v;
  }
}

}  // namespace selfsense::identification
