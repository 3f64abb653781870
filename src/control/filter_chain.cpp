#include "selfsense/control/filter_chain.hpp"

#include <cassert>
#include <string>

#include "selfsense/control/parameter_error.hpp"

namespace selfsense::control {

FilterChain::FilterChain(std::span<const BiquadCoefficients> sections) : size_(sections.size()) {
  require_valid(sections.size() <= kMaxSections,
                "FilterChain.sections: " + std::to_string(sections.size()) + " sections, at most " +
                    std::to_string(kMaxSections));
  for (std::size_t i = 0; i < size_; ++i) {
    std::string why;
    if (!sections[i].is_valid(&why)) {
      throw ParameterError("FilterChain.sections[" + std::to_string(i) + "]: " + why);
    }
    sections_[i] = Biquad(sections[i]);
  }
}

const BiquadCoefficients& FilterChain::section(std::size_t i) const noexcept {
  assert(i < size_);
  return sections_[i].coefficients();
}

bool FilterChain::set_section(std::size_t i, const BiquadCoefficients& coefficients) noexcept {
  return i < size_ && sections_[i].set_coefficients(coefficients);
}

bool FilterChain::assign(std::span<const BiquadCoefficients> sections, double input) noexcept {
  if (sections.size() > kMaxSections) return false;
  for (const BiquadCoefficients& c : sections) {
    if (!c.is_stable()) return false;
  }
  double x = input;
  for (std::size_t i = 0; i < sections.size(); ++i) {
    const BiquadCoefficients& next = sections[i];
    if (i >= size_ || !(sections_[i].coefficients() == next)) {
      static_cast<void>(sections_[i].set_coefficients(next));
      sections_[i].reset(x);
    }
    x *= next.dc_gain();
  }
  size_ = sections.size();
  return true;
}

void FilterChain::reset(double x) noexcept {
  for (std::size_t i = 0; i < size_; ++i) {
    sections_[i].reset(x);
    x *= sections_[i].coefficients().dc_gain();
  }
}

double FilterChain::dc_gain() const noexcept {
  double gain = 1.0;
  for (std::size_t i = 0; i < size_; ++i)
    gain *= sections_[i].coefficients().dc_gain();
  return gain;
}

std::complex<double> FilterChain::response(double frequency, double sample_time) const noexcept {
  std::complex<double> h{1.0, 0.0};
  for (std::size_t i = 0; i < size_; ++i)
    h *= sections_[i].coefficients().response(frequency, sample_time);
  return h;
}

void FilterChain::save_state(std::span<double> out) const noexcept {
  assert(out.size() >= state_size());
  for (std::size_t i = 0; i < size_; ++i)
    sections_[i].save_state(out.subspan(i * Biquad::kStateSize, Biquad::kStateSize));
}

void FilterChain::restore_state(std::span<const double> in) noexcept {
  assert(in.size() >= state_size());
  for (std::size_t i = 0; i < size_; ++i)
    sections_[i].restore_state(in.subspan(i * Biquad::kStateSize, Biquad::kStateSize));
}

}  // namespace selfsense::control
