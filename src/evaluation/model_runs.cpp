#include "selfsense/evaluation/model_runs.hpp"

#include <span>

#include "selfsense/adaptation/adapted_reconstruction.hpp"

namespace selfsense::evaluation {

ModelRuns run_model(const models::TransducerModel& model, const FieldSignals& signals, bool forward,
                    bool reconstruct) {
  const models::Drive drive = model.drive();
  const std::span<const double> x = signals.drive(drive);
  const std::span<const double> y = signals.sensed(drive);
  const std::size_t n = signals.size();
  const models::RuntimeOptions options{signals.sample_time};
  ModelRuns runs;
  runs.sample_time = signals.sample_time;
  if (forward) {
    models::Simulation sim(model, options);
    runs.rediscretised = sim.rediscretised();
    const bool sensor = model.sensor || (model.vectorial && model.vectorial->sensor);
    const bool actuator = model.actuator || (model.vectorial && model.vectorial->actuator);
    if (sensor) runs.sensed.resize(n);
    if (actuator) runs.strain.resize(n);
    runs.forward_status.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
      if (!signals.temp.empty()) sim.set_temperature(signals.temp[k]);
      const double stress = signals.stress.empty() ? 0.0 : signals.stress[k];
      const models::Simulation::Output out = sim.step(x[k], stress);
      if (sensor) runs.sensed[k] = out.sensed;
      if (actuator) runs.strain[k] = out.strain;
      runs.forward_status[k] = static_cast<double>(out.status);
    }
    runs.forward_counts = sim.counts();
  }
  if (reconstruct && models::can_reconstruct(model) && !y.empty()) {
    models::Reconstruction rec(model, options);
    runs.rediscretised = rec.rediscretised();
    runs.stress_hat.resize(n);
    if (rec.has_strain()) runs.strain_hat.resize(n);
    runs.estimate_status.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
      if (!signals.temp.empty()) rec.set_temperature(signals.temp[k]);
      const models::Reconstruction::Estimate est = rec.step(x[k], y[k]);
      runs.stress_hat[k] = est.stress;
      if (rec.has_strain()) runs.strain_hat[k] = est.strain;
      runs.estimate_status[k] = static_cast<double>(est.status);
    }
    runs.estimate_counts = rec.counts();
  }
  return runs;
}

std::string describe(const models::StatusCounts& counts) {
  std::string out;
  for (std::size_t i = 0; i < models::kSampleStatusCount; ++i) {
    const auto s = static_cast<models::SampleStatus>(i);
    if (counts[s] == 0) continue;
    if (!out.empty()) out += ", ";
    out += std::string(models::to_string(s)) + " " + std::to_string(counts[s]);
  }
  return out.empty() ? "no samples" : out;
}

nlohmann::json to_json(const models::StatusCounts& counts) {
  nlohmann::json out = nlohmann::json::object();
  for (std::size_t i = 0; i < models::kSampleStatusCount; ++i) {
    const auto s = static_cast<models::SampleStatus>(i);
    out[std::string(models::to_string(s))] = counts[s];
  }
  return out;
}

std::vector<ChannelFigures> figures(const models::TransducerModel& model,
                                    const FieldSignals& signals, const ModelRuns& runs,
                                    std::size_t from, std::size_t to) {
  std::vector<ChannelFigures> out;
  const auto add = [&](const char* name, const std::vector<double>& reference,
                       const std::vector<double>& estimate) {
    if (reference.empty() || estimate.empty() || to <= from) return;
    out.push_back(
        {name, identification::fit_quality(std::span(reference).subspan(from, to - from),
                                           std::span(estimate).subspan(from, to - from))});
  };
  const bool field = model.drive() == models::Drive::kField;
  add(field ? "D" : "E", field ? signals.d : signals.e, runs.sensed);
  add("S", signals.s, runs.strain);
  add("T_hat", signals.stress, runs.stress_hat);
  add("S_hat", signals.s, runs.strain_hat);
  return out;
}

std::vector<ChannelFigures> figures(const models::TransducerModel& model,
                                    const FieldSignals& signals) {
  return figures(model, signals, run_model(model, signals, true, true), 0, signals.size());
}

nlohmann::json to_json(const std::vector<ChannelFigures>& figures) {
  nlohmann::json out = nlohmann::json::object();
  for (const ChannelFigures& f : figures) {
    out[f.channel] = {{"nrmse", f.figures.nrmse}, {"max", f.figures.max}};
  }
  return out;
}

AdaptedRuns run_adapted(const models::TransducerModel& model, const FieldSignals& signals,
                        const std::vector<double>& temperature) {
  adaptation::DriftEstimatorConfig config{};
  config.frozen = !temperature.empty();
  adaptation::AdaptedReconstruction adapted(model, config, signals.sample_time);
  const std::span<const double> x = signals.drive(model.drive());
  const std::span<const double> y = signals.sensed(model.drive());
  const std::size_t n = signals.size();
  AdaptedRuns runs;
  runs.stress_hat.resize(n);
  runs.strain_hat.resize(adapted.has_strain() ? n : 0);
  runs.estimate_status.resize(n);
  runs.temp_equivalent.resize(n);
  runs.permittivity_drift.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    if (!temperature.empty()) adapted.set_temperature(temperature[k]);
    const adaptation::AdaptedReconstruction::Estimate est = adapted.step(x[k], y[k]);
    runs.stress_hat[k] = est.stress;
    if (!runs.strain_hat.empty()) runs.strain_hat[k] = est.strain;
    runs.estimate_status[k] = static_cast<double>(est.status);
    runs.temp_equivalent[k] = adapted.drift().temperature_degc;
    runs.permittivity_drift[k] = adapted.drift().permittivity;
  }
  runs.counts = adapted.counts();
  runs.updates = adapted.estimator().updates();
  runs.last = adapted.drift();
  return runs;
}

}  // namespace selfsense::evaluation
