// Runs a transducer model over a whole recording (forward and reconstruction, through the
// runtime model types at the recording's sample rate) and computes the fit figures of
// docs/recording-format.md per channel.
#pragma once

#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "selfsense/adaptation/drift_estimator.hpp"
#include "selfsense/evaluation/field_signals.hpp"
#include "selfsense/identification/fit_quality.hpp"
#include "selfsense/models/runtime_model.hpp"
#include "selfsense/models/transducer_model.hpp"

namespace selfsense::evaluation {

struct ModelRuns {
  std::vector<double> sensed{};  // D_model (field drive) or E_model (charge drive)
  std::vector<double> strain{};  // S_model
  std::vector<double> stress_hat{};
  std::vector<double> strain_hat{};
  std::vector<double> forward_status{};   // models::SampleStatus codes per sample
  std::vector<double> estimate_status{};  // of the reconstruction
  models::StatusCounts forward_counts{};
  models::StatusCounts estimate_counts{};
  double sample_time{0.0};    // [s] the model ran at (the recording's)
  bool rediscretised{false};  // the model was identified at another sample time
};

// Forward with the recorded stress (0 where the recording has none); reconstruction where the
// model has a sensor side with a coupling and the recording the sensed channel. The recorded
// temperature, where there is one, feeds the corrections' temperature terms.
[[nodiscard]] ModelRuns run_model(const models::TransducerModel& model, const FieldSignals& signals,
                                  bool forward, bool reconstruct);
// "ok 148199, input_out_of_range 1"
[[nodiscard]] std::string describe(const models::StatusCounts& counts);
[[nodiscard]] nlohmann::json to_json(const models::StatusCounts& counts);

struct ChannelFigures {
  std::string channel{};  // D (or E), S, T_hat, S_hat
  identification::FitQuality figures{};
};

// Figures on samples [from, to) of every channel that has both a model output and a reference.
[[nodiscard]] std::vector<ChannelFigures> figures(const models::TransducerModel& model,
                                                  const FieldSignals& signals,
                                                  const ModelRuns& runs, std::size_t from,
                                                  std::size_t to);

// The figures of forward and reconstruction over the whole recording.
[[nodiscard]] std::vector<ChannelFigures> figures(const models::TransducerModel& model,
                                                  const FieldSignals& signals);

[[nodiscard]] nlohmann::json to_json(const std::vector<ChannelFigures>& figures);

// `reconstruct --adapt` (docs/adaptation.md): the adapted reconstruction over the recording, with
// the equivalent temperature and the permittivity drift per sample. With a temperature [degC] per
// sample the drift estimate is frozen and follows that temperature instead.
struct AdaptedRuns {
  std::vector<double> stress_hat{};
  std::vector<double> strain_hat{};  // empty without a strain estimate
  std::vector<double> estimate_status{};
  std::vector<double> temp_equivalent{};     // [degC]
  std::vector<double> permittivity_drift{};  // [1]
  models::StatusCounts counts{};
  std::size_t updates{0};  // of the drift estimate
  adaptation::Drift last{};
};
[[nodiscard]] AdaptedRuns run_adapted(const models::TransducerModel& model,
                                      const FieldSignals& signals,
                                      const std::vector<double>& temperature);

}  // namespace selfsense::evaluation
