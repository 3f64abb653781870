// Fit figures as docs/recording-format.md defines them: the RMS and the largest absolute
// value of (recorded - model), each divided by the recorded channel's range (max - min).
#pragma once

#include <span>

namespace selfsense::identification {

struct FitQuality {
  double nrmse{0.0};
  double max{0.0};
};

// Throws std::invalid_argument if the sizes differ or are zero.
[[nodiscard]] FitQuality fit_quality(std::span<const double> recorded,
                                     std::span<const double> model);

}  // namespace selfsense::identification
