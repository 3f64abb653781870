#include "model_runs.hpp"

#include <cstdio>
#include <optional>
#include <span>

#include "selfsense/models/reconstructor.hpp"
#include "selfsense/models/stress_hysteresis.hpp"

namespace selfsense::cli {

namespace {

// The stress-dependent model: forward from E and T, numerical reconstruction from E and D.
ModelRuns run_vectorial(const models::StressHysteresisModel& m, const FieldSignals& signals,
                        bool forward, bool reconstruct) {
  const std::size_t n = signals.size();
  ModelRuns runs;
  if (forward) {
    models::StressHysteresisForward f(m);
    if (m.sensor) runs.sensed.resize(n);
    if (m.actuator) runs.strain.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
      const double stress = signals.stress.empty() ? 0.0 : signals.stress[k];
      const models::StressHysteresisForward::Output out = f.step(signals.e[k], stress);
      if (m.sensor) runs.sensed[k] = out.sensed;
      if (m.actuator) runs.strain[k] = out.strain;
    }
  }
  if (reconstruct && m.sensor && !signals.d.empty()) {
    models::StressHysteresisReconstructor r(m);
    runs.stress_hat.resize(n);
    if (m.actuator) runs.strain_hat.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
      const models::StressHysteresisReconstructor::Estimate est =
          r.step(signals.e[k], signals.d[k]);
      runs.stress_hat[k] = est.stress;
      if (m.actuator) runs.strain_hat[k] = est.strain;
    }
    const auto& c = r.status_counts();
    runs.solver_failures = n - c[static_cast<std::size_t>(models::SolveStatus::kOk)];
    if (runs.solver_failures > 0) {
      static_cast<void>(std::fprintf(
          stderr,
          "warning: stress not uniquely reconstructed at %zu of %zu samples (no solution "
          "%zu, D-T not monotone %zu, not converged %zu)\n",
          runs.solver_failures, n, c[1], c[2], c[3]));
    }
  }
  return runs;
}

}  // namespace

ModelRuns run_model(const models::TransducerModel& model, const FieldSignals& signals, bool forward,
                    bool reconstruct) {
  if (model.vectorial) return run_vectorial(*model.vectorial, signals, forward, reconstruct);
  const models::Drive drive = model.drive();
  const std::span<const double> x = signals.drive(drive);
  const std::span<const double> y = signals.sensed(drive);
  const std::size_t n = signals.size();
  ModelRuns runs;
  if (forward) {
    models::ForwardModel f(model);
    if (model.sensor) runs.sensed.resize(n);
    if (model.actuator) runs.strain.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
      const double stress = signals.stress.empty() ? 0.0 : signals.stress[k];
      const models::ForwardModel::Output out = f.step(x[k], stress);
      if (model.sensor) runs.sensed[k] = out.sensed;
      if (model.actuator) runs.strain[k] = out.strain;
    }
  }
  const bool coupled = model.sensor && !model.sensor->linear_gains.empty() &&
                       model.sensor->linear_gains.front() != 0.0;
  if (reconstruct && coupled && !y.empty()) {
    models::Reconstructor r(model);
    runs.stress_hat.resize(n);
    if (model.actuator) runs.strain_hat.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
      const models::Reconstructor::Estimate est = r.step(x[k], y[k]);
      runs.stress_hat[k] = est.stress;
      if (model.actuator) runs.strain_hat[k] = est.strain;
    }
  }
  return runs;
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

nlohmann::json to_json(const std::vector<ChannelFigures>& figures) {
  nlohmann::json out = nlohmann::json::object();
  for (const ChannelFigures& f : figures) {
    out[f.channel] = {{"nrmse", f.figures.nrmse}, {"max", f.figures.max}};
  }
  return out;
}

}  // namespace selfsense::cli
