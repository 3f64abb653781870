#include "selfsense/operators/regressor_stream.hpp"

#include <algorithm>
#include <cassert>

#include "selfsense/operators/kernels.hpp"

namespace selfsense::operators {

RegressorStream::RegressorStream(const OperatorBasis& basis, std::span<const double> history)
    : basis_(&basis),
      plays_(basis.plays(), history.empty() ? 0.0 : history.front()),
      spare_(basis.plays()),
      lags_(basis.creep()),
      row_(basis.columns()) {
  for (const double h : history)
    kernels::play_bank_step(h, basis.thresholds, plays_);
  const std::size_t n_eig = basis.eigenvalues.size();
  for (std::size_t i = 0; i < basis.creep_rows.size(); ++i) {
    std::fill_n(lags_.begin() + static_cast<std::ptrdiff_t>(i * n_eig), n_eig,
                plays_[basis.creep_rows[i]]);
  }
}

std::span<const double> RegressorStream::next(double x) noexcept {
  const OperatorBasis& b = *basis_;
  // The plays step into the spare buffer, and each difference clamps its two plays from the
  // old state again: reading back plays just stored, unaligned, stalled the loop on store
  // forwarding (a fifth of this function's time in `selfsense diagnose`). The same arithmetic.
  const std::size_t n = plays_.size();
  const double* r = b.thresholds.data();
  const double* old = plays_.data();
  double* stepped = spare_.data();
  const auto clamp = [x, r, old](std::size_t i) {
    return std::min(std::max(old[i], x - r[i]), x + r[i]);
  };
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const double p = clamp(i);
    stepped[i] = p;
    row_[i] = p - clamp(i + 1);
  }
  stepped[n - 1] = clamp(n - 1);
  row_[n - 1] = stepped[n - 1];
  plays_.swap(spare_);
  step_lags();
  std::copy(lags_.begin(), lags_.end(), row_.begin() + static_cast<std::ptrdiff_t>(n));
  std::size_t c = n + lags_.size();
  for (std::size_t h = 0; h < b.hinge_rows.size(); ++h)
    row_[c++] = std::max(plays_[b.hinge_rows[h]] - b.hinge_levels[h], 0.0);
  return row_;
}

void RegressorStream::skip(std::span<const double> xs) noexcept {
  for (const double x : xs) {
    kernels::play_bank_step(x, basis_->thresholds, plays_);
    step_lags();
  }
}

// z_rj += a_j (p_r - z_rj) from the plays just stepped.
void RegressorStream::step_lags() noexcept {
  const OperatorBasis& b = *basis_;
  const std::size_t n_eig = b.eigenvalues.size();
  for (std::size_t i = 0; i < b.creep_rows.size(); ++i) {
    const double p = plays_[b.creep_rows[i]];
    for (std::size_t j = 0; j < n_eig; ++j) {
      double& z = lags_[i * n_eig + j];
      z += b.gains[j] * (p - z);
    }
  }
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

}  // namespace selfsense::operators
