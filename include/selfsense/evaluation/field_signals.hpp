// A recording's channels in field quantities (E, D, S, T), converted from terminal quantities
// (u, q, x, F) through a geometry where the field columns are absent.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "selfsense/io/recording.hpp"
#include "selfsense/models/geometry.hpp"
#include "selfsense/models/transducer_model.hpp"

namespace selfsense::evaluation {

struct FieldSignals {
  std::string source{};          // file name, for messages
  std::vector<double> t{};       // [s]
  std::vector<double> e{};       // [V/m]; empty if absent
  std::vector<double> d{};       // [C/m^2]
  std::vector<double> s{};       // [-]
  std::vector<double> stress{};  // [Pa]
  std::vector<double> temp{};    // [degC]; empty if absent
  double sample_time{0.0};       // mean step of t [s]

  [[nodiscard]] std::size_t size() const noexcept { return t.size(); }
  // The drive and sensed channel for a structure (E/D, or D/E for charge drive).
  [[nodiscard]] std::span<const double> drive(models::Drive which) const noexcept;
  [[nodiscard]] std::span<const double> sensed(models::Drive which) const noexcept;
};

// Reads E (or u), D (or q), S (or x), T (or F) as present; a terminal column needs `geometry`.
// Requires a strictly increasing, uniformly sampled t (steps within 5 % of their mean) and the
// drive channel of `drive`; throws io::RecordingError naming the file and what is missing.
[[nodiscard]] FieldSignals field_signals(const io::Recording& recording, const std::string& source,
                                         const std::optional<models::Geometry>& geometry,
                                         models::Drive drive);

}  // namespace selfsense::evaluation
