#include "selfsense/adaptation/temperature_fit.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "selfsense/adaptation/adapted_reconstruction.hpp"
#include "selfsense/models/reconstructor.hpp"

namespace selfsense::adaptation {

namespace {

constexpr std::size_t kMax = 6;

// Normal equations of one side, accumulated row by row (at most six columns).
class SideNormal {
 public:
  explicit SideNormal(std::size_t columns) : n_{columns} {}
  void add(const std::array<double, kMax>& x, double y) {
    for (std::size_t i = 0; i < n_; ++i) {
      b_[i] += x[i] * y;
      for (std::size_t j = 0; j < n_; ++j)
        a_[i][j] += x[i] * x[j];
    }
    yy_ += y * y;
    ++rows_;
  }
  // Solves with the columns scaled to unit norm and a small ridge; zero where a column is zero.
  [[nodiscard]] std::array<double, kMax> solve() const {
    std::array<double, kMax> scale{};
    for (std::size_t i = 0; i < n_; ++i)
      scale[i] = a_[i][i] > 0.0 ? 1.0 / std::sqrt(a_[i][i]) : 0.0;
    std::array<std::array<double, kMax + 1>, kMax> m{};
    for (std::size_t i = 0; i < n_; ++i) {
      for (std::size_t j = 0; j < n_; ++j)
        m[i][j] = a_[i][j] * scale[i] * scale[j];
      m[i][i] += scale[i] > 0.0 ? 1e-9 : 1.0;
      m[i][n_] = b_[i] * scale[i];
    }
    for (std::size_t c = 0; c < n_; ++c) {  // Gaussian elimination, partial pivoting
      std::size_t pivot = c;
      for (std::size_t r = c + 1; r < n_; ++r) {
        if (std::abs(m[r][c]) > std::abs(m[pivot][c])) pivot = r;
      }
      std::swap(m[c], m[pivot]);
      for (std::size_t r = 0; r < n_; ++r) {
        if (r == c) continue;
        const double f = m[r][c] / m[c][c];
        for (std::size_t j = c; j <= n_; ++j)
          m[r][j] -= f * m[c][j];
      }
    }
    std::array<double, kMax> x{};
    for (std::size_t i = 0; i < n_; ++i)
      x[i] = m[i][n_] / m[i][i] * scale[i];
    return x;
  }
  // RMS of the residual y - x' theta.
  [[nodiscard]] double rms(const std::array<double, kMax>& theta) const {
    double sum = yy_;
    for (std::size_t i = 0; i < n_; ++i) {
      sum -= 2.0 * theta[i] * b_[i];
      for (std::size_t j = 0; j < n_; ++j)
        sum += theta[i] * a_[i][j] * theta[j];
    }
    return rows_ > 0 ? std::sqrt(std::max(0.0, sum) / static_cast<double>(rows_)) : 0.0;
  }

 private:
  std::size_t n_;
  std::array<std::array<double, kMax>, kMax> a_{};
  std::array<double, kMax> b_{};
  double yy_{0.0};
  std::size_t rows_{0};
};

// The three parts times dtheta (and dtheta^2), in the order linear, loop, coupling.
std::array<double, kMax> columns(double linear, double loop, double coupled, double dt,
                                 bool quadratic) {
  if (!quadratic) return {linear * dt, loop * dt, coupled * dt, 0.0, 0.0, 0.0};
  const double dt2 = dt * dt;
  return {linear * dt, linear * dt2, loop * dt, loop * dt2, coupled * dt, coupled * dt2};
}

models::SideTemperature side_of(const std::array<double, kMax>& x, bool quadratic) {
  if (!quadratic) return {{x[0], 0.0}, {x[1], 0.0}, {x[2], 0.0}};
  return {{x[0], x[1]}, {x[2], x[3]}, {x[4], x[5]}};
}

// How many of the intervals [lo + i w, lo + (i + 1) w) the temperature visits (at most
// kManyLevels counted).
std::size_t temperature_levels(const std::vector<TemperatureFitInput>& recordings, double lo,
                               double w) {
  constexpr std::size_t kManyLevels = 1000;
  std::vector<bool> seen(kManyLevels, false);
  std::size_t levels = 0;
  for (const TemperatureFitInput& in : recordings) {
    for (const double temp : in.temperature) {
      if (!std::isfinite(temp)) continue;
      const double i = std::floor((temp - lo) / w);
      if (!(i >= 0.0) || i >= static_cast<double>(kManyLevels)) return kManyLevels;
      const auto index = static_cast<std::size_t>(i);
      if (!seen[index]) {
        seen[index] = true;
        ++levels;
      }
    }
  }
  return levels;
}

// The rows of every recording, per side and for the increments.
struct Normals {
  SideNormal sensor;
  SideNormal actuator;
  SideNormal increments{4};
};

// Adds one recording's rows: the model run along it from its start state.
void add_recording(const models::TransducerModel& model, const TemperatureFitInput& in,
                   double reference_degc, bool quadratic, double min_field_step_v_per_m,
                   double max_interval_s, Normals& normals, TemperatureFitResult& out) {
  models::Reconstructor kernel(model);
  models::SideOperator& s = *kernel.sensor();
  models::SideOperator& a = *kernel.actuator();
  const SideSplit sensor_split(s);
  const SideSplit actuator_split(a);
  // The estimator's gate (drift_estimator.hpp): the anchor's E, D, L_s, H_s, T and age.
  struct Anchor {
    double e, d, l, h, t, age;
  };
  Anchor anchor{};
  bool anchored = false;
  const double sample_time = model.sample_time;
  for (std::size_t k = 0; k < in.field.size(); ++k) {
    const double e = in.field[k];
    const double fixed_s = s.offset() + s.quadratic() * e * e;
    const double fixed_a = a.offset() + a.quadratic() * e * e;
    const SideSplit::Parts ps = sensor_split.split(s, e, s.step_unloaded(e) - fixed_s);
    const SideSplit::Parts pa = actuator_split.split(a, e, a.step_unloaded(e) - fixed_a);
    const double dt = in.temperature[k] - reference_degc;
    const double t = in.stress[k];
    const double ys = in.sensed[k] - fixed_s - ps.linear - ps.loop - s.coupling() * t;
    const double ya = in.strain[k] - fixed_a - pa.linear - pa.loop - a.coupling() * t;
    const auto xs = columns(ps.linear, ps.loop, s.coupling() * t, dt, quadratic);
    const auto xa = columns(pa.linear, pa.loop, a.coupling() * t, dt, quadratic);
    const bool finite =
        std::isfinite(ys) && std::isfinite(ya) &&
        std::all_of(xs.begin(), xs.end(), [](double v) { return std::isfinite(v); }) &&
        std::all_of(xa.begin(), xa.end(), [](double v) { return std::isfinite(v); });
    if (!finite) {
      anchored = false;
      continue;
    }
    normals.sensor.add(xs, ys);
    normals.actuator.add(xa, ya);
    ++out.samples;
    const double d = in.sensed[k] - fixed_s;
    if (!anchored || anchor.age > max_interval_s) {
      anchored = true;
      anchor = {e, d, ps.linear, ps.loop, t, 0.0};
      continue;
    }
    anchor.age += sample_time;
    if (!(std::abs(e - anchor.e) >= min_field_step_v_per_m)) continue;
    const double dl = ps.linear - anchor.l;
    const double dh = ps.loop - anchor.h;
    const double dstress = s.coupling() * (t - anchor.t);
    normals.increments.add({dl * dt, dh * dt, dstress, dstress * dt, 0.0, 0.0},
                           d - anchor.d - dl - dh - dstress);
    anchor = {e, d, ps.linear, ps.loop, t, 0.0};
    ++out.increments;
  }
}

}  // namespace

TemperatureFitResult fit_temperature(const models::TransducerModel& model,
                                     const TemperatureFitInput& in, double reference_degc,
                                     bool quadratic, double min_span_k,
                                     double min_field_step_v_per_m, double max_interval_s) {
  return fit_temperature(model, std::vector<TemperatureFitInput>{in}, reference_degc, quadratic,
                         min_span_k, min_field_step_v_per_m, max_interval_s);
}

TemperatureFitResult fit_temperature(const models::TransducerModel& model,
                                     const std::vector<TemperatureFitInput>& recordings,
                                     double reference_degc, bool quadratic, double min_span_k,
                                     double min_field_step_v_per_m, double max_interval_s) {
  if (model.drive() != models::Drive::kField || model.vectorial || !model.sensor ||
      !model.actuator) {
    throw std::invalid_argument{
        "temperature fit: needs a field-driven model with a sensor and an actuator side"};
  }
  if (model.sensed_correction || model.strain_correction) {
    throw std::invalid_argument{
        "temperature fit: a model with diagnosed corrections is not fitted"};
  }
  if (!std::isfinite(reference_degc)) {
    throw std::invalid_argument{"temperature fit: the reference temperature must be finite"};
  }
  // Per recording in the messages only where there are several.
  const auto which = [&recordings](std::size_t i) {
    return recordings.size() > 1 ? "recording " + std::to_string(i) + ": " : std::string{};
  };
  std::size_t total = 0;
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < recordings.size(); ++i) {
    const TemperatureFitInput& in = recordings[i];
    const std::size_t n = in.field.size();
    if (in.sensed.size() != n || in.stress.size() != n || in.strain.size() != n ||
        in.temperature.size() != n) {
      throw std::invalid_argument{"temperature fit: " + which(i) + "the columns differ in length"};
    }
    total += n;
    if (n == 0) continue;
    const auto [l, h] = std::minmax_element(in.temperature.begin(), in.temperature.end());
    lo = std::min(lo, *l);
    hi = std::max(hi, *h);
  }
  if (total < 100) throw std::invalid_argument{"temperature fit: fewer than 100 samples"};
  if (!(hi - lo >= min_span_k)) {
    throw std::invalid_argument{"temperature fit: the temperature spans " +
                                std::to_string(hi - lo) + " K, less than " +
                                std::to_string(min_span_k) + " K"};
  }

  TemperatureFitResult out;
  out.quadratic = quadratic && temperature_levels(recordings, lo, min_span_k) >= 3;
  quadratic = out.quadratic;
  const std::size_t cols = quadratic ? 6 : 3;
  Normals normals{SideNormal(cols), SideNormal(cols)};
  for (const TemperatureFitInput& in : recordings) {
    add_recording(model, in, reference_degc, quadratic, min_field_step_v_per_m, max_interval_s,
                  normals, out);
  }
  const std::array<double, kMax> ts = normals.sensor.solve();
  const std::array<double, kMax> ta = normals.actuator.solve();
  out.coefficients.reference_degc = reference_degc;
  out.coefficients.sensor = side_of(ts, quadratic);
  out.coefficients.actuator = side_of(ta, quadratic);
  out.sensor_rms_before = normals.sensor.rms({});
  out.sensor_rms_after = normals.sensor.rms(ts);
  out.actuator_rms_before = normals.actuator.rms({});
  out.actuator_rms_after = normals.actuator.rms(ta);
  if (out.increments >= 100) {
    const std::array<double, kMax> ti = normals.increments.solve();
    out.coefficients.increments = {ti[0], ti[1]};
  }
  return out;
}

}  // namespace selfsense::adaptation
