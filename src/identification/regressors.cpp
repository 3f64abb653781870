#include "selfsense/identification/regressors.hpp"

#include <algorithm>
#include <cassert>

#include "selfsense/operators/kernels.hpp"

namespace selfsense::identification {

RegressorStream::RegressorStream(const OperatorBasis& basis, std::span<const double> history)
    : basis_(&basis),
      plays_(basis.plays(), history.empty() ? 0.0 : history.front()),
      lags_(basis.creep()),
      row_(basis.columns()) {
  for (const double h : history)
    operators::kernels::play_bank_step(h, basis.thresholds, plays_);
  const std::size_t n_eig = basis.eigenvalues.size();
  for (std::size_t i = 0; i < basis.creep_rows.size(); ++i) {
    std::fill_n(lags_.begin() + static_cast<std::ptrdiff_t>(i * n_eig), n_eig,
                plays_[basis.creep_rows[i]]);
  }
}

std::span<const double> RegressorStream::next(double x) noexcept {
  const OperatorBasis& b = *basis_;
  operators::kernels::play_bank_step(x, b.thresholds, plays_);
  const std::size_t n = plays_.size();
  for (std::size_t i = 0; i + 1 < n; ++i)
    row_[i] = plays_[i] - plays_[i + 1];
  row_[n - 1] = plays_[n - 1];
  const std::size_t n_eig = b.eigenvalues.size();
  std::size_t c = n;
  for (std::size_t i = 0; i < b.creep_rows.size(); ++i) {
    const double p = plays_[b.creep_rows[i]];
    for (std::size_t j = 0; j < n_eig; ++j) {
      double& z = lags_[i * n_eig + j];
      z += b.gains[j] * (p - z);
      row_[c++] = z;
    }
  }
  return row_;
}

void RegressorStream::save_state(std::span<double> out) const noexcept {
  assert(out.size() == state_size());
  std::copy(plays_.begin(), plays_.end(), out.begin());
  std::copy(lags_.begin(), lags_.end(), out.begin() + static_cast<std::ptrdiff_t>(plays_.size()));
}

void RegressorStream::restore_state(std::span<const double> in) noexcept {
  assert(in.size() == state_size());
  std::copy_n(in.begin(), plays_.size(), plays_.begin());
  std::copy(in.begin() + static_cast<std::ptrdiff_t>(plays_.size()), in.end(), lags_.begin());
}

void DeadZoneBasis::evaluate(double v, std::span<double> out) const noexcept {
  assert(out.size() == columns());
  const auto side = [v](const std::vector<double>& d, bool up, std::span<double> cols) {
    double first = 0.0;
    for (std::size_t j = 0; j < d.size(); ++j) {
      const double zj = up ? std::max(v - d[j], 0.0) : std::min(v - d[j], 0.0);
      const double zn =
          j + 1 < d.size() ? (up ? std::max(v - d[j + 1], 0.0) : std::min(v - d[j + 1], 0.0)) : 0.0;
      if (j == 0) first = zj;
      cols[j] = zj - zn;
    }
    return first;
  };
  const double zu1 = side(upper, true, out.subspan(1, upper.size()));
  const double zl1 = side(lower, false, out.subspan(1 + upper.size(), lower.size()));
  out[0] = v - zu1 - zl1;
}

operators::DeadZoneSuperposition::Params DeadZoneBasis::superposition(
    std::span<const double> slopes) const {
  assert(slopes.size() == columns());
  operators::DeadZoneSuperposition::Params p;
  p.linear_weight = slopes[0];
  double previous = slopes[0];
  for (std::size_t j = 0; j < upper.size(); ++j) {
    p.upper_thresholds.push_back(upper[j]);
    p.upper_weights.push_back(slopes[1 + j] - previous);
    previous = slopes[1 + j];
  }
  previous = slopes[0];
  for (std::size_t j = 0; j < lower.size(); ++j) {
    p.lower_thresholds.push_back(lower[j]);
    p.lower_weights.push_back(slopes[1 + upper.size() + j] - previous);
    previous = slopes[1 + upper.size() + j];
  }
  return p;
}

DeadZoneBasis spread_dead_zones(std::span<const double> v, std::size_t per_side) {
  DeadZoneBasis out;
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  const double span = *hi - *lo;
  for (std::size_t j = 1; j <= per_side; ++j) {
    const double f = static_cast<double>(j) / static_cast<double>(per_side + 1);
    if (*hi > 0.05 * span) out.upper.push_back(f * *hi);
    if (*lo < -0.05 * span) out.lower.push_back(f * *lo);
  }
  return out;
}

}  // namespace selfsense::identification
