#include "selfsense/evaluation/field_signals.hpp"

#include <algorithm>
#include <cmath>
#include <functional>

#include "selfsense/base/format_number.hpp"

namespace selfsense::evaluation {
namespace {

// The field column if present, else the terminal column converted, else empty.
std::vector<double> channel(const io::Recording& rec, const std::string& source,
                            const std::optional<models::Geometry>& geometry, const char* field,
                            const char* terminal,
                            double (models::Geometry::*convert)(double) const) {
  if (rec.has(field)) {
    const auto c = rec.column(field);
    return {c.begin(), c.end()};
  }
  if (!rec.has(terminal)) return {};
  if (!geometry) {
    throw io::RecordingError(source + ": column '" + terminal + "' is a terminal quantity; " +
                             "converting it to '" + field + "' needs the transducer geometry");
  }
  const auto c = rec.column(terminal);
  std::vector<double> out(c.size());
  std::transform(c.begin(), c.end(), out.begin(),
                 [&](double v) { return std::invoke(convert, *geometry, v); });
  return out;
}

}  // namespace

std::span<const double> FieldSignals::drive(models::Drive which) const noexcept {
  return which == models::Drive::kField ? std::span<const double>(e) : std::span<const double>(d);
}

std::span<const double> FieldSignals::sensed(models::Drive which) const noexcept {
  return which == models::Drive::kField ? std::span<const double>(d) : std::span<const double>(e);
}

FieldSignals field_signals(const io::Recording& rec, const std::string& source,
                           const std::optional<models::Geometry>& geometry, models::Drive drive) {
  FieldSignals out;
  out.source = source;
  const auto t = rec.column("t");
  out.t.assign(t.begin(), t.end());
  if (out.t.size() < 2) throw io::RecordingError(source + ": needs at least two samples");
  out.e = channel(rec, source, geometry, "E", "u", &models::Geometry::field);
  out.d = channel(rec, source, geometry, "D", "q", &models::Geometry::displacement_density);
  out.s = channel(rec, source, geometry, "S", "x", &models::Geometry::strain);
  out.stress = channel(rec, source, geometry, "T", "F", &models::Geometry::stress);
  if (rec.has("temp")) {
    const auto temp = rec.column("temp");
    out.temp.assign(temp.begin(), temp.end());
  }
  const char* needed = drive == models::Drive::kField ? "E (or u)" : "D (or q)";
  if (out.drive(drive).empty()) {
    throw io::RecordingError(source + ": missing the drive column " + needed);
  }
  const std::size_t n = out.t.size();
  out.sample_time = (out.t.back() - out.t.front()) / static_cast<double>(n - 1);
  for (std::size_t k = 1; k < n; ++k) {
    const double dt = out.t[k] - out.t[k - 1];
    if (std::abs(dt - out.sample_time) > 0.05 * out.sample_time) {
      throw io::RecordingError(source + ": column 't': not uniformly sampled: step " +
                               base::format_number(dt) + " s at data row " + std::to_string(k + 1) +
                               ", mean step " + base::format_number(out.sample_time) + " s");
    }
  }
  return out;
}

}  // namespace selfsense::evaluation
