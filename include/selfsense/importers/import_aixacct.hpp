// Reader for aixACCT aixPlorer "Export as ASCII" files (.dat): a PiezoResult summary, then one
// block per measurement: a line "Table <n>", "Key: value" metadata, a tab-separated header that
// starts with "Time [s]" and the rows up to the next blank line.
//
// One block becomes a recording (docs/recording-format.md), h the sample thickness, A its
// electrode area:
//   E = (V+ - V-) / h              [V/m]
//   D = P1 * 1e-2 - I0 * (t - t0) / A   [C/m^2]  (P1 in uC/cm2 is the integrated current / A)
//   S = D1 * 1e-9 / h              [-]      (D1: interferometer displacement in nm)
// I0 is a constant leakage/offset current (0 unless asked for): the analyser integrates it into
// P1, which then ramps during long holds. The raw columns u (V), I (A), P1 (uC/cm2) and D1 (nm)
// are carried through unchanged. Not real-time code; errors name the file and line.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "selfsense/io/recording.hpp"

namespace selfsense::importers {

struct AixacctOptions {
  int block{1};                              // n of "Table <n>" (data blocks only)
  std::optional<double> area_mm2{};          // overrides "Area [mm2]"
  std::optional<double> thickness_m{};       // overrides "Thickness [nm]"
  std::optional<double> current_offset_a{};  // I0 given
  // I0 estimated as the mean of I1 over the block's last `detrend_tail` share of samples: valid
  // where the block ends in a constant-voltage hold (the displacement current has died out).
  bool detrend_charge{false};
  double detrend_tail{0.2};
};

struct AixacctImport {
  io::Recording recording{};
  double offset_current_a{0.0};  // I0 removed from D
  std::string sample_name{};
};

[[nodiscard]] AixacctImport import_aixacct(const std::filesystem::path& path,
                                           const AixacctOptions& options);

}  // namespace selfsense::importers
