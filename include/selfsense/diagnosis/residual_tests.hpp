// Residual analysis of a model against a recording (pure math):
//   whiteness      r_ee(tau) = sum_k e[k] e[k+tau] / sum_k e[k]^2, tau = 0 .. L
//   independence   r_eu(tau) = sum_k e[k+tau] u[k] / sqrt(sum e^2 sum u^2), tau = -L .. L
// (means removed). Under white residuals both are about N(0, 1/N), so +-z/sqrt(N) with
// z = 2.576 is the 99 % bound (MATLAB's resid does the same with L = 25).
// Segments: where the moving RMS of the residual (window of 1 % of the record, at least 16
// samples) exceeds `factor` times the RMS of the whole residual; neighbours closer than a window
// are merged and the strongest `max_segments` kept, in time order.
// Holds: stretches of at least 1 % of the record (and 16 samples) in which the drive stays within
// 5 % of its range of the level it stepped to; the step leading into a hold (a ramp of shorter
// stretches, at most as long as the shortest hold) belongs to it. A continuous drive has none.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

namespace selfsense::diagnosis {

struct CorrelationTest {
  int max_lag{25};
  std::vector<double> autocorrelation{};    // lags 0 .. max_lag
  std::vector<double> cross_correlation{};  // lags -max_lag .. max_lag
  double bound{0.0};                        // 99 % confidence bound
  // Share of lags 1..L (auto) and -L..L (cross) outside the bound.
  double auto_outside{0.0};
  double cross_outside{0.0};
};

[[nodiscard]] CorrelationTest correlation_test(std::span<const double> residual,
                                               std::span<const double> input, int max_lag = 25);

struct Segment {
  std::size_t begin{0};  // samples [begin, end)
  std::size_t end{0};
};

[[nodiscard]] std::vector<Segment> large_segments(std::span<const double> residual, double factor,
                                                  std::size_t max_segments);

[[nodiscard]] std::vector<Segment> holds_of(std::span<const double> drive);

}  // namespace selfsense::diagnosis
