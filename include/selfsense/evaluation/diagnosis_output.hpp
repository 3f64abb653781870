// What `selfsense diagnose` (docs/diagnose.md) writes of a diagnosis::Result: its JSON file and
// the input of its HTML report (report/diagnose_report.hpp), with the diagnosis's sample ranges
// turned into times of the recording.
#pragma once

#include <nlohmann/json.hpp>
#include <vector>

#include "selfsense/diagnosis/diagnosis.hpp"
#include "selfsense/evaluation/field_signals.hpp"
#include "selfsense/evaluation/model_runs.hpp"
#include "selfsense/models/transducer_model.hpp"
#include "selfsense/report/diagnose_report.hpp"

namespace selfsense::evaluation {

// Samples [begin, end) as the times of their first and last sample.
[[nodiscard]] std::vector<report::ReportSegment> seconds(
    const std::vector<diagnosis::Segment>& segments, const std::vector<double>& t);

[[nodiscard]] std::vector<report::ReportFigure> report_figures(
    const std::vector<ChannelFigures>& figures);

// verdict, findings, unexplained and channels; the fit figures are the caller's to add.
[[nodiscard]] nlohmann::json to_json(const diagnosis::Result& result, const std::vector<double>& t);

// The report's verdict, sentences, signals, channels and findings; the paths and the fit figures
// are the caller's to add.
[[nodiscard]] report::ReportInput report_input(const diagnosis::Result& result,
                                               const FieldSignals& recording, models::Drive drive);

}  // namespace selfsense::evaluation
