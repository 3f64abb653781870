// Scalar root finding for reconstruction without a closed-form inverse (paper eq. 3-4): find T
// in [lo, hi] with f(T) = 0, where f(T) = D_model(E, T) - D_measured at the current sample.
//
// The inverse exists and is unique on the bracket only if f is continuous and strictly
// monotone there (the paper's condition on the D-T characteristic). The solver checks this on
// a grid of `probes` points before iterating and reports, never hides, what it finds:
//   kOk            a root, f strictly monotone on the bracket
//   kNoSolution    f has one sign on the whole bracket: the measured D is out of the model's
//                  reach; value is the bracket end nearest to a solution
//   kNotMonotone   f changes direction on the bracket: the inverse may not be unique; value is
//                  the root in the first sub-bracket with a sign change
//   kNotConverged  the iteration limit was hit; value is the best estimate
// Illinois (modified regula falsi) iteration: superlinear, and the bracket always shrinks.
// Real-time safe: no allocation, no exceptions, at most probes + max_iterations evaluations.
#pragma once

#include <cmath>
#include <cstdint>

namespace selfsense::models {

enum class SolveStatus : std::uint8_t { kOk, kNoSolution, kNotMonotone, kNotConverged };

struct SolveResult {
  double value{0.0};
  SolveStatus status{SolveStatus::kOk};
  int evaluations{0};
};

struct SolverOptions {
  double tolerance{1e-12};  // relative to the bracket width
  int max_iterations{60};
  int probes{8};  // grid points of the monotonicity check (>= 2)
};

template <typename F>
SolveResult solve_bracketed(F&& f, double lo, double hi, const SolverOptions& opt = {}) noexcept {
  SolveResult out;
  const double tol = opt.tolerance * std::abs(hi - lo);
  const int probes = opt.probes < 2 ? 2 : opt.probes;
  // Monotonicity check and the first sign change on the probe grid.
  double a = lo;
  double fa = f(lo);
  ++out.evaluations;
  double b = hi;
  double fb = 0.0;
  bool found = false;
  int direction = 0;
  double x_prev = lo;
  double f_prev = fa;
  for (int i = 1; i < probes; ++i) {
    const double x = lo + (hi - lo) * static_cast<double>(i) / static_cast<double>(probes - 1);
    const double fx = f(x);
    ++out.evaluations;
    const int dir = fx > f_prev ? 1 : (fx < f_prev ? -1 : 0);
    if (dir == 0 || (direction != 0 && dir != direction)) out.status = SolveStatus::kNotMonotone;
    if (direction == 0) direction = dir;
    if (!found && ((f_prev <= 0.0 && fx >= 0.0) || (f_prev >= 0.0 && fx <= 0.0))) {
      a = x_prev;
      fa = f_prev;
      b = x;
      fb = fx;
      found = true;
    }
    x_prev = x;
    f_prev = fx;
  }
  if (!found) {
    // Same sign everywhere: report the end where |f| is smaller.
    out.value = std::abs(fa) < std::abs(f_prev) ? lo : hi;
    out.status = SolveStatus::kNoSolution;
    return out;
  }
  if (fa == 0.0 || fb == 0.0) {
    out.value = fa == 0.0 ? a : b;
    return out;
  }
  // Illinois iteration on [a, b].
  int side = 0;
  double c_prev = a;
  for (int it = 0; it < opt.max_iterations; ++it) {
    const double c = (a * fb - b * fa) / (fb - fa);
    const double fc = f(c);
    ++out.evaluations;
    if (std::abs(b - a) < tol || std::abs(c - c_prev) < tol || fc == 0.0) {
      out.value = c;
      return out;
    }
    c_prev = c;
    if ((fc > 0.0) == (fb > 0.0)) {
      b = c;
      fb = fc;
      if (side == -1) fa *= 0.5;
      side = -1;
    } else {
      a = c;
      fa = fc;
      if (side == 1) fb *= 0.5;
      side = 1;
    }
    if (std::abs(b - a) < tol) {
      out.value = 0.5 * (a + b);
      return out;
    }
  }
  out.value = 0.5 * (a + b);
  if (out.status == SolveStatus::kOk) out.status = SolveStatus::kNotConverged;
  return out;
}

}  // namespace selfsense::models
