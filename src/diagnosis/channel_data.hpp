// One output channel under diagnosis (D, S, or E under charge drive): the recording, the base
// model's output, and what the candidates read besides.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "selfsense/models/side_model.hpp"

namespace selfsense::diagnosis::detail {

struct ChannelData {
  std::string name;
  bool sensed{false};
  std::span<const double> recorded;
  std::vector<double> base;
  double coupling{0.0};                    // of the stress in the model's side
  std::span<const double> sensed_model{};  // the model's sensed response (electrostriction)
  bool affine{true};  // not the stress-hysteresis model: the response is G[x] + y0
};

// A channel's response to the drive alone, r = y - coupling T (y itself without a stress).
[[nodiscard]] std::vector<double> response_to_drive(std::span<const double> y, double coupling,
                                                    std::span<const double> stress);

// Non-finite model outputs (a rejected first sample) are held at the last finite value so no
// filter state sees them; the result marks the samples that were finite.
[[nodiscard]] std::vector<bool> hold_finite(std::vector<double>& y);

// The stress coupling of a side (its first linear gain), 0 without one.
[[nodiscard]] double coupling_of(const std::optional<models::SideModel>& side);

}  // namespace selfsense::diagnosis::detail
