// The HTML report of `selfsense diagnose` (docs/diagnose-report.md): one self-contained file,
// inline SVG plots, no scripts or network resources. The diagnosis fills ReportInput; this file
// only draws it.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace selfsense::report {

struct ReportSegment {
  double t_start{0.0};  // [s]
  double t_end{0.0};
};

// Residual correlation test of one channel (MATLAB resid style): normalised autocorrelation of
// the residual at lags 0..max_lag and its cross-correlation with the drive input at lags
// -max_lag..max_lag, each against +-bound (99 % confidence of white noise).
struct ReportCorrelation {
  std::string channel{};
  int max_lag{25};
  std::vector<double> autocorrelation{};    // max_lag + 1 values, lag 0 first (1.0)
  std::vector<double> cross_correlation{};  // 2 max_lag + 1 values, lag -max_lag first
  double bound{0.0};
};

struct ReportFigure {
  std::string channel{};  // "S", "D", "T_hat", "S_hat"
  double nrmse{0.0};
  double max{0.0};
};

struct ReportFinding {
  std::string effect{};  // docs/diagnose.md "What each effect becomes": creep, charge_leakage, ...
  std::string channel{};
  std::vector<ReportSegment> where{};
  double explains{0.0};  // share of the residual variance removed
  std::string evidence{};
  // Other effects that explain nearly as much of the same residual, with their evidence.
  struct Alternative {
    std::string effect{};
    double explains{0.0};
    std::string evidence{};
  };
  std::vector<Alternative> alternatives{};
  // Residual (before) against the feature that explains it, for the scatter plot.
  std::string feature_name{};  // e.g. "log10 time since last step [s]"
  std::vector<double> feature{};
  std::vector<double> residual{};
};

// One output channel of the recording, before and after the added physics.
struct ReportChannel {
  std::string name{};  // "S" or "D"
  std::string unit{};  // "-" or "C/m^2"
  std::vector<double> recorded{};
  std::vector<double> before{};          // model output before
  std::vector<double> after{};           // model output after
  std::vector<ReportSegment> located{};  // where the residual is large or structured
  ReportCorrelation test_before{};
  ReportCorrelation test_after{};
};

struct ReportInput {
  std::string model_path{};
  std::string recording_path{};
  std::string validate_path{};  // empty without --validate
  std::string verdict{};        // "mismatch", "unexplained" or "consistent"
  // One sentence per residual well above the noise floor that no candidate reduces.
  std::vector<std::string> unexplained{};
  std::vector<double> t{};      // [s]
  std::vector<double> drive{};  // the drive input (E [V/m], or D for charge drive)
  std::string drive_name{"E"};
  std::string drive_unit{"V/m"};
  std::vector<ReportChannel> channels{};
  std::vector<ReportFinding> findings{};
  std::vector<ReportFigure> fit_before{};
  std::vector<ReportFigure> fit_after{};
  std::vector<ReportFigure> validation_before{};  // empty without --validate
  std::vector<ReportFigure> validation_after{};
};

// Writes the report; throws std::runtime_error naming the path when it cannot be written.
// Long series are reduced for drawing (min and max per pixel column), so the file stays small
// for 1e6-sample recordings.
void write_diagnosis_report(const ReportInput& input, const std::filesystem::path& path);

}  // namespace selfsense::report
