#include "selfsense/adaptation/trend_filter.hpp"

#include <algorithm>
#include <cmath>

namespace selfsense::adaptation {

void TrendFilter::update(double x, double t_s) noexcept {
  if (!std::isfinite(x) || !std::isfinite(t_s)) return;
  last_ = x;
  if (count_ == 0.0) {
    y1_ = x;
    y2_ = x;
  } else {
    const double dt = std::max(0.0, t_s - t_);
    y1_ += (1.0 - std::exp(-dt / tau1_)) * (x - y1_);
    y2_ += (1.0 - std::exp(-dt / tau2_)) * (x - y2_);
  }
  t_ = t_s;
  count_ += 1.0;
}

double TrendFilter::slope() const noexcept {
  return count_ > 1.0 ? (y1_ - y2_) / (tau2_ - tau1_) : 0.0;
}

void TrendFilter::clear() noexcept {
  y1_ = 0.0;
  y2_ = 0.0;
  t_ = 0.0;
  count_ = 0.0;
  last_ = 0.0;
}

void TrendFilter::save_state(std::span<double> out) const noexcept {
  if (out.size() < kStateSize) return;
  out[0] = y1_;
  out[1] = y2_;
  out[2] = t_;
  out[3] = count_;
  out[4] = last_;
}

void TrendFilter::restore_state(std::span<const double> in) noexcept {
  if (in.size() < kStateSize) return;
  y1_ = in[0];
  y2_ = in[1];
  t_ = in[2];
  count_ = std::max(0.0, in[3]);
  last_ = in[4];
}

}  // namespace selfsense::adaptation
