#include "selfsense/plant/preisach.hpp"

#include <algorithm>
#include <cmath>

namespace selfsense::plant {

namespace {

double density(const HysteresisConfig& c, double alpha, double beta) {
  const double w = 0.5 * (alpha - beta);
  const double b = 0.5 * (alpha + beta);
  const double sigma_b =
      c.bias_sigma_v_per_m * (b > c.bias_center_v_per_m ? 1.0 + c.asymmetry : 1.0 - c.asymmetry);
  const double dw = (w - c.width_center_v_per_m) / c.width_sigma_v_per_m;
  const double db = (b - c.bias_center_v_per_m) / sigma_b;
  return std::exp(-0.5 * (dw * dw + db * db));
}

}  // namespace

EverettTable::EverettTable(const HysteresisConfig& config)
    : n_{static_cast<std::size_t>(std::max(config.levels, 2))},
      lo_{config.field_min_v_per_m},
      hi_{config.field_max_v_per_m},
      step_{(config.field_max_v_per_m - config.field_min_v_per_m) /
            static_cast<double>(std::max(config.levels, 2) - 1)},
      table_(n_ * n_, 0.0) {
  // Cell (p, q) covers alpha in [x_p, x_p+1], beta in [x_q, x_q+1]; its weight is the density at
  // a sub-sampled set of points (4 x 4), the diagonal cell counting only beta <= alpha.
  const std::size_t cells = n_ - 1;
  std::vector<double> weight(cells * cells, 0.0);
  constexpr int kSub{4};
  for (std::size_t p = 0; p < cells; ++p) {
    for (std::size_t q = 0; q <= p; ++q) {
      double sum = 0.0;
      for (int sa = 0; sa < kSub; ++sa) {
        for (int sb = 0; sb < kSub; ++sb) {
          const double fa = (sa + 0.5) / kSub;
          const double fb = (sb + 0.5) / kSub;
          if (p == q && fb > fa) continue;
          const double alpha = lo_ + (static_cast<double>(p) + fa) * step_;
          const double beta = lo_ + (static_cast<double>(q) + fb) * step_;
          sum += density(config, alpha, beta);
        }
      }
      weight[p * cells + q] = sum;
    }
  }
  // F(x_i, x_j) = sum of cells with j <= q <= p < i. Row recursion over i:
  // F(i, j) = F(i-1, j) + sum_{q=j}^{i-1} w(i-1, q).
  for (std::size_t i = 1; i < n_; ++i) {
    double row_tail = 0.0;
    for (std::size_t jj = i; jj-- > 0;) {
      row_tail += weight[(i - 1) * cells + jj];
      table_[i * n_ + jj] = table_[(i - 1) * n_ + jj] + row_tail;
    }
  }
  const double total = table_[(n_ - 1) * n_];
  if (total > 0.0) {
    for (double& v : table_)
      v /= total;
  }
}

double EverettTable::operator()(double a, double b) const noexcept {
  a = std::clamp(a, lo_, hi_);
  b = std::clamp(b, lo_, hi_);
  if (b >= a) return 0.0;
  const double ua = (a - lo_) / step_;
  const double ub = (b - lo_) / step_;
  const auto last = static_cast<double>(n_ - 2);
  const double ia = std::min(std::floor(ua), last);
  const double ib = std::min(std::floor(ub), last);
  const double fa = ua - ia;
  const double fb = ub - ib;
  const auto i = static_cast<std::size_t>(ia);
  const auto j = static_cast<std::size_t>(ib);
  const double f00 = node(i, j);
  const double f01 = node(i, j + 1);
  const double f10 = node(i + 1, j);
  const double f11 = node(i + 1, j + 1);
  return (1.0 - fa) * ((1.0 - fb) * f00 + fb * f01) + fa * ((1.0 - fb) * f10 + fb * f11);
}

void PreisachState::reset(const EverettTable& table, double input) noexcept {
  points_[0] = table.field_min();
  partial_[0] = 0.0;
  size_ = 1;
  output_ = -1.0;
  update(table, input);
}

void PreisachState::recompute_last(const EverettTable& table) noexcept {
  const std::size_t i = size_ - 1;
  if (i == 0) {
    partial_[0] = 0.0;
    return;
  }
  // Odd indices are maxima (they add the triangle below them), even indices minima (they
  // remove the triangle between the preceding maximum and themselves).
  const double term =
      (i % 2 == 1) ? table(points_[i], points_[i - 1]) : -table(points_[i - 1], points_[i]);
  partial_[i] = partial_[i - 1] + term;
}

double PreisachState::update(const EverettTable& table, double input) noexcept {
  const double u = std::clamp(input, table.field_min(), table.field_max());
  if (size_ == 1) {
    if (u > points_[0]) {
      points_[1] = u;
      size_ = 2;
    }
  } else {
    const bool rising = points_[size_ - 1] > points_[size_ - 2];
    const double last = points_[size_ - 1];
    if (u == last) return output_;
    if ((u > last) == rising) {
      points_[size_ - 1] = u;  // same direction: the segment grows
    } else {
      if (size_ == kCapacity) {
        // Full: merge the innermost loop (drop its two turning points).
        points_[size_ - 3] = points_[size_ - 1];
        size_ -= 2;
        recompute_last(table);
      }
      points_[size_] = u;  // reversal: the last input becomes a turning point
      ++size_;
    }
    // Wiping out: the new input erases every loop it has closed.
    while (size_ >= 3) {
      const bool now_rising = points_[size_ - 1] > points_[size_ - 2];
      const double previous = points_[size_ - 3];
      const bool wipes = now_rising ? u >= previous : u <= previous;
      if (!wipes) break;
      points_[size_ - 3] = u;
      size_ -= 2;
    }
    if (size_ == 2 && points_[1] <= points_[0]) size_ = 1;
  }
  // Wiping may leave stale partial sums only for the last point.
  recompute_last(table);
  output_ = 2.0 * partial_[size_ - 1] - 1.0;
  return output_;
}

}  // namespace selfsense::plant
