#include "selfsense/plant/creep_bank.hpp"

#include <algorithm>
#include <cmath>

namespace selfsense::plant {

CreepBank::CreepBank(const std::vector<double>& tau_s, const std::vector<double>& weights,
                     double sample_time_s)
    : n_{std::min({tau_s.size(), weights.size(), kMaxCreepElements})} {
  for (std::size_t j = 0; j < n_; ++j) {
    a_[j] = -std::expm1(-sample_time_s / tau_s[j]);
    w_[j] = weights[j];
  }
}

void CreepBank::reset(double y) noexcept {
  y0_ = y;
  for (std::size_t j = 0; j < n_; ++j)
    z_[j] = y;
}

double CreepBank::peek(double y) const noexcept {
  double creep = 0.0;
  for (std::size_t j = 0; j < n_; ++j)
    creep += w_[j] * ((z_[j] + a_[j] * (y - z_[j])) - y0_);
  return creep;
}

double CreepBank::update(double y) noexcept {
  double creep = 0.0;
  for (std::size_t j = 0; j < n_; ++j) {
    z_[j] = z_[j] + a_[j] * (y - z_[j]);
    creep += w_[j] * (z_[j] - y0_);
  }
  return creep;
}

}  // namespace selfsense::plant
