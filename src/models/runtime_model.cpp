#include "selfsense/models/runtime_model.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "carry_over.hpp"
#include "selfsense/base/check.hpp"

namespace selfsense::models {
namespace {

constexpr double kNoValue = std::numeric_limits<double>::quiet_NaN();

// The model with its sides discretised for the loop's sample time.
TransducerModel at_sample_time(TransducerModel model, double ts) {
  model.sample_time = ts;
  if (model.sensor) model.sensor->sample_time = ts;
  if (model.actuator) model.actuator->sample_time = ts;
  if (model.vectorial) model.vectorial->sample_time = ts;
  return model;
}

double loop_sample_time(const TransducerModel& model, const RuntimeOptions& options) {
  std::string why;
  if (!options.is_valid(&why)) throw std::invalid_argument(why);
  return options.sample_time > 0.0 ? options.sample_time : model.sample_time;
}

detail::OperatorMemory memory_of(const operators::HysteresisCreep& op) noexcept {
  const std::span<const double> state = op.state();
  const std::size_t n = op.play_thresholds().size();
  return {op.play_thresholds(), state.first(n), op.params().creep.thresholds,
          op.params().creep.eigenvalues, state.subspan(n)};
}

detail::OperatorMemory memory_of(const operators::RegressorStream& stream) noexcept {
  return {stream.basis().thresholds, stream.plays(), {}, {}, {}};
}

// Creep thresholds of a regressor stream are a subset of its plays; the stress-dependent model
// has none, so its carry-over is plays only.
void adopt_side(const detail::ModelMemory& from, SideOperator& side,
                std::span<double> scratch) noexcept {
  operators::HysteresisCreep& op = side.op();
  const std::span<double> state = scratch.first(op.state().size());
  detail::carry_over(from, op.play_thresholds(), op.params().creep.thresholds,
                     op.params().creep.eigenvalues, state);
  op.set_state(state);
}

void adopt_stream(const detail::ModelMemory& from, operators::RegressorStream& stream,
                  std::span<double> scratch) noexcept {
  const std::span<double> state = scratch.first(stream.state_size());
  detail::carry_over(from, stream.basis().thresholds, {}, {}, state);
  stream.restore_state(state);
}

// The input before the first sample: the last turning point of the identified history.
double initial_input(const TransducerModel& model) noexcept {
  const std::vector<double>* h = nullptr;
  if (model.vectorial) {
    h = &model.vectorial->history;
  } else if (model.sensor) {
    h = &model.sensor->history;
  } else if (model.actuator) {
    h = &model.actuator->history;
  }
  return (h != nullptr && !h->empty()) ? h->back() : 0.0;
}

// The variants hold the affine kernels by value and the vectorial ones (not movable) by pointer.
// Dispatched with get_if, not std::visit: visit may throw bad_variant_access, and these run in
// noexcept real-time code.
template <typename Affine, typename Vectorial, typename F>
decltype(auto) dispatch(std::variant<Affine, std::unique_ptr<Vectorial>>& impl, F&& f) noexcept {
  if (auto* a = std::get_if<Affine>(&impl)) return f(*a);
  return f(**std::get_if<std::unique_ptr<Vectorial>>(&impl));
}
template <typename Affine, typename Vectorial, typename F>
decltype(auto) dispatch(const std::variant<Affine, std::unique_ptr<Vectorial>>& impl,
                        F&& f) noexcept {
  if (const auto* a = std::get_if<Affine>(&impl)) return f(*a);
  return f(**std::get_if<std::unique_ptr<Vectorial>>(&impl));
}

using Stages = std::optional<CorrectionStage>* [2];
using ConstStages = const std::optional<CorrectionStage>* const[2];

template <typename Impl>
std::size_t kernel_size(const Impl& impl) noexcept {
  return dispatch(impl, [](const auto& m) { return m.state_size(); });
}

// The kernel's state first, then each correction stage's.
template <typename Impl>
bool save_into(const Impl& impl, ConstStages& stages, const ModelIdentity& identity,
               SavedState& out) noexcept {
  if (out.values.size() != identity.state_size) return false;
  const std::size_t n = kernel_size(impl);
  const std::span<double> all(out.values);
  dispatch(impl, [&](const auto& m) { m.save_state(all.first(n)); });
  std::size_t at = n;
  for (const auto* stage : stages) {
    if (!stage->has_value()) continue;
    (*stage)->save_state(all.subspan(at, CorrectionStage::state_size()));
    at += CorrectionStage::state_size();
  }
  out.identity = identity;
  return true;
}

template <typename Impl>
RestoreResult restore_from(Impl& impl, Stages& stages, const ModelIdentity& identity,
                           const SavedState& in) noexcept {
  if (in.identity.structure != identity.structure ||
      in.identity.parameter_hash != identity.parameter_hash) {
    return RestoreResult::kWrongModel;
  }
  if (in.identity.state_size != identity.state_size || in.values.size() != identity.state_size) {
    return RestoreResult::kWrongSize;
  }
  const std::size_t n = kernel_size(impl);
  const std::span<const double> all(in.values);
  dispatch(impl, [&](auto& m) { m.restore_state(all.first(n)); });
  std::size_t at = n;
  for (auto* stage : stages) {
    if (!stage->has_value()) continue;
    (*stage)->restore_state(all.subspan(at, CorrectionStage::state_size()));
    at += CorrectionStage::state_size();
  }
  return RestoreResult::kOk;
}

std::optional<CorrectionStage> stage_for(const std::optional<ChannelCorrection>& c, double ts) {
  if (!c || c->empty()) return std::nullopt;
  return CorrectionStage(*c, ts);
}

double reference_temperature(const TransducerModel& model) noexcept {
  if (model.sensed_correction) return model.sensed_correction->temperature_reference_degc;
  if (model.strain_correction) return model.strain_correction->temperature_reference_degc;
  return 25.0;
}

// A late reference sensor of S is the bench's, not the actuator's: the reconstruction's S_hat
// does not take its delay (it would only add loop latency).
std::optional<ChannelCorrection> without_delay(std::optional<ChannelCorrection> c) {
  if (c) c->delay_s = 0.0;
  return c;
}

// Hot swap of the same correction: its filters, lags and delay lines carry on (a restarted
// leakage inverse would drop the charge it has restored so far).
void adopt_stage(std::optional<CorrectionStage>& into,
                 const std::optional<CorrectionStage>& from) noexcept {
  if (!into || !from || !(into->correction() == from->correction())) return;
  std::array<double, CorrectionStage::state_size()> state{};
  from->save_state(state);
  into->restore_state(state);
}

double coupling_of(const std::optional<SideModel>& side) noexcept {
  return (side && !side->linear_gains.empty()) ? side->linear_gains.front() : 0.0;
}

std::size_t stages_size(const std::optional<CorrectionStage>& a,
                        const std::optional<CorrectionStage>& b) noexcept {
  return (a ? CorrectionStage::state_size() : 0) + (b ? CorrectionStage::state_size() : 0);
}

// One step behind the input gate (header comment): a rejected sample advances the kernel with
// the last accepted inputs held and returns that estimate with the rejecting status.
template <typename Out, typename Kernel>
Out gated_step(const detail::InputGate& gate, detail::HeldInputs& held, Out& last,
               StatusCounts& counts, double first, double second, Kernel&& kernel) noexcept {
  const SampleStatus status = gate.check(first, second);
  if (status != SampleStatus::kOk) {
    counts.add(status);
    if (held.valid) {
      const SampleStatus previous = last.status;
      last = kernel(held.first, held.second);
      last.status = previous;
    }
    Out out = last;
    out.status = status;
    return out;
  }
  const Out out = kernel(first, second);
  counts.add(out.status);
  held = {first, second, true};
  last = out;
  return out;
}

}  // namespace

bool RuntimeOptions::is_valid(std::string* why) const {
  namespace check = base::check;
  return check::finite("runtime.sample_time", sample_time, why) &&
         check::require(sample_time >= 0.0, "runtime.sample_time", sample_time,
                        "must be >= 0 (0: the model's own)", why) &&
         check::non_negative("runtime.range_margin", range_margin, why);
}

namespace detail {

InputGate::InputGate(const std::optional<InputRange>& first,
                     const std::optional<InputRange>& second, double margin) noexcept {
  const std::optional<InputRange>* ranges[2] = {&first, &second};
  for (std::size_t i = 0; i < 2; ++i) {
    if (!ranges[i]->has_value()) continue;
    const InputRange& r = **ranges[i];
    ranged_[i] = true;
    lo_[i] = r.min - margin * r.span();
    hi_[i] = r.max + margin * r.span();
  }
}

SampleStatus InputGate::check(double first, double second) const noexcept {
  if (!std::isfinite(first) || !std::isfinite(second)) return SampleStatus::kInputNotFinite;
  const double x[2] = {first, second};
  for (std::size_t i = 0; i < 2; ++i) {
    if (ranged_[i] && (x[i] < lo_[i] || x[i] > hi_[i])) return SampleStatus::kInputOutOfRange;
  }
  return SampleStatus::kOk;
}

}  // namespace detail

// ---- Reconstruction ----

namespace {

std::variant<Reconstructor, std::unique_ptr<StressSidesReconstructor>> make_reconstruction(
    const TransducerModel& model) {
  if (model.vectorial) return std::make_unique<StressSidesReconstructor>(model);
  return Reconstructor(model);
}

std::variant<ForwardModel, std::unique_ptr<StressSidesForward>> make_simulation(
    const TransducerModel& model) {
  if (model.vectorial) return std::make_unique<StressSidesForward>(model);
  return ForwardModel(model);
}

}  // namespace

Reconstruction::Reconstruction(const TransducerModel& model, const RuntimeOptions& options)
    : impl_(make_reconstruction(at_sample_time(model, loop_sample_time(model, options)))),
      gate_(model.drive_range, model.sensed_range, options.range_margin),
      sample_time_(loop_sample_time(model, options)),
      identified_ts_(model.sample_time),
      last_{0.0, kNoValue, SampleStatus::kOk},
      sensed_fix_(stage_for(model.sensed_correction, sample_time_)),
      strain_fix_(stage_for(without_delay(model.strain_correction), sample_time_)),
      temperature_(reference_temperature(model)),
      sensed_coupling_(coupling_of(model.sensor)),
      strain_coupling_(coupling_of(model.actuator)) {
  std::string why;
  if (model.sensed_correction && !model.sensed_correction->invertible("corrections.sensed", &why)) {
    throw std::invalid_argument(why);
  }
  if (model.sensed_correction && model.vectorial && model.vectorial->sensor) {
    // A stress-dependent sensor's response to the stress is not a coupling times T, so neither
    // the response to the drive alone nor a solve of the stress through the correction exists
    // (a plain sensor beside a stress-dependent actuator has both: plain_sensor_step).
    const auto& c = *model.sensed_correction;
    const char* key = !c.creep_weights.empty()            ? "creep_weights"
                      : c.stress_gain_per_pa != 0.0       ? "stress_gain_per_pa"
                      : c.stress_quadratic_per_pa2 != 0.0 ? "stress_quadratic_per_pa2"
                      : c.stress_drive_per_pa != 0.0      ? "stress_drive_per_pa"
                      : c.stress_linear_per_pa != 0.0     ? "stress_linear_per_pa"
                                                          : nullptr;
    if (key != nullptr) {
      throw std::invalid_argument(
          std::string("corrections.sensed.") + key +
          ": follows the sensor's response to the drive alone or to the stress, which the "
          "stress-hysteresis model does not separate");
    }
  }
  if (model.sensed_correction && sensed_coupling_ == 0.0) {
    const auto& c = *model.sensed_correction;
    const char* key = c.stress_quadratic_per_pa2 != 0.0 ? "stress_quadratic_per_pa2"
                      : c.stress_drive_per_pa != 0.0    ? "stress_drive_per_pa"
                      : c.stress_linear_per_pa != 0.0   ? "stress_linear_per_pa"
                      : c.stress_gain_per_pa != 0.0     ? "stress_gain_per_pa"
                                                        : nullptr;
    if (key != nullptr) {
      throw std::invalid_argument(std::string("corrections.sensed.") + key +
                                  ": needs a sensor side with a stress coupling to be solved in "
                                  "the reconstruction");
    }
  }
  identity_ = {model.structure, parameter_hash(model),
               kernel_size(impl_) + stages_size(sensed_fix_, strain_fix_)};
  scratch_.resize(identity_.state_size);
  held_.first = initial_input(model);
}

bool Reconstruction::has_strain() const noexcept {
  if (const auto* affine = std::get_if<Affine>(&impl_)) return affine->actuator().has_value();
  return std::get<Vectorial>(impl_)->has_strain();
}

Reconstruction::Estimate Reconstruction::step(double drive, double sensed) noexcept {
  return gated_step(gate_, held_, last_, counts_, drive, sensed,
                    [this](double x, double y) { return kernel_step(x, y); });
}

// A stress-hysteresis strain part beside a plain sensor (stress_sides.hpp): as the affine
// kernel, T_hat from the plain sensor with the sensed correction between the phases, then the
// strain part at the corrected T_hat. x and y become the drive and sensed value as corrected.
Reconstruction::Estimate Reconstruction::plain_sensor_step(StressSidesReconstructor& v, double& x,
                                                           double& y) noexcept {
  if (sensed_fix_) x = sensed_fix_->delay_drive(x);
  const double response = v.sensed_response(x);
  const double read = (sensed_fix_ && sensed_fix_->reads_response()) ? response : 0.0;
  if (sensed_fix_) y = sensed_fix_->invert(y, {0.0, x, 0.0, temperature_, 0.0, read});
  double stress = (y - response) / v.sensor_coupling();
  if (sensed_fix_) {
    stress =
        sensed_fix_->solve_stress(stress, sensed_coupling_, {0.0, x, 0.0, temperature_, 0.0, read});
  }
  return {stress, v.strain_at(x, stress), SampleStatus::kOk};
}

Reconstruction::Estimate Reconstruction::kernel_step(double drive, double sensed) noexcept {
  double x = drive;
  double y = sensed;
  Estimate out{};
  auto* affine = std::get_if<Affine>(&impl_);
  auto* vectorial = std::get_if<Vectorial>(&impl_);
  if (vectorial != nullptr && (*vectorial)->plain_sensing()) {
    out = plain_sensor_step(**vectorial, x, y);
  } else {
    double response = 0.0;  // G_s[x] + y0_s, when the sensed correction's creep follows it
    const bool split = sensed_fix_ && sensed_fix_->reads_response() && affine != nullptr;
    if (sensed_fix_) {
      x = sensed_fix_->delay_drive(drive);
      if (split) response = affine->sensed_response(x);
      y = sensed_fix_->invert(sensed, {0.0, x, 0.0, temperature_, 0.0, response});
    }
    if (affine != nullptr) {
      const Reconstructor::Estimate e = split ? affine->finish(x, y, response) : affine->step(x, y);
      out = {e.stress, e.strain, SampleStatus::kOk};
    } else {
      const StressSidesReconstructor::Estimate e = (*vectorial)->step(x, y);
      out = {e.stress, e.strain, e.status};
    }
    if (sensed_fix_ && sensed_coupling_ != 0.0) {
      const double stress = sensed_fix_->solve_stress(out.stress, sensed_coupling_,
                                                      {0.0, x, 0.0, temperature_, 0.0, response});
      out.strain += strain_coupling_ * (stress - out.stress);
      out.stress = stress;
    }
  }
  if (strain_fix_) {
    // The electrostriction term reads the sensed response to the drive alone, as forward.
    out.strain = strain_fix_->step({out.strain, x, out.stress, temperature_,
                                    y - sensed_coupling_ * out.stress,
                                    out.strain - strain_coupling_ * out.stress});
  }
  return out;
}

SavedState Reconstruction::make_saved_state() const {
  return {identity_, std::vector<double>(identity_.state_size, 0.0)};
}

bool Reconstruction::save_state(SavedState& out) const noexcept {
  ConstStages stages{&sensed_fix_, &strain_fix_};
  return save_into(impl_, stages, identity_, out);
}

RestoreResult Reconstruction::restore_state(const SavedState& in) noexcept {
  Stages stages{&sensed_fix_, &strain_fix_};
  return restore_from(impl_, stages, identity_, in);
}

void Reconstruction::memory(detail::ModelMemory& out) const noexcept {
  out.last_input = held_.first;
  if (const auto* affine = std::get_if<Affine>(&impl_)) {
    if (affine->sensor()) out.add(memory_of(affine->sensor()->op()));
    if (affine->actuator()) out.add(memory_of(affine->actuator()->op()));
  } else {
    const StressSidesReconstructor& v = *std::get<Vectorial>(impl_);
    out.add(memory_of(v.stream()));
    if (const SideOperator* side = v.plain_sensor()) out.add(memory_of(side->op()));
    if (const SideOperator* side = v.plain_actuator()) out.add(memory_of(side->op()));
  }
}

void Reconstruction::adopt_state(const Reconstruction& running) noexcept {
  detail::ModelMemory from;
  running.memory(from);
  if (auto* affine = std::get_if<Affine>(&impl_)) {
    if (affine->sensor()) adopt_side(from, *affine->sensor(), scratch_);
    if (affine->actuator()) adopt_side(from, *affine->actuator(), scratch_);
  } else {
    StressSidesReconstructor& v = *std::get<Vectorial>(impl_);
    adopt_stream(from, v.stream(), scratch_);
    if (SideOperator* side = v.plain_sensor()) adopt_side(from, *side, scratch_);
    if (SideOperator* side = v.plain_actuator()) adopt_side(from, *side, scratch_);
  }
  adopt_stage(sensed_fix_, running.sensed_fix_);
  adopt_stage(strain_fix_, running.strain_fix_);
  held_ = running.held_;
  last_ = running.last_;
}

// ---- Simulation ----

Simulation::Simulation(const TransducerModel& model, const RuntimeOptions& options)
    : impl_(make_simulation(at_sample_time(model, loop_sample_time(model, options)))),
      gate_(model.drive_range, std::nullopt, options.range_margin),
      sample_time_(loop_sample_time(model, options)),
      identified_ts_(model.sample_time),
      last_{kNoValue, kNoValue, SampleStatus::kOk},
      sensed_fix_(stage_for(model.sensed_correction, sample_time_)),
      strain_fix_(stage_for(model.strain_correction, sample_time_)),
      temperature_(reference_temperature(model)),
      sensed_coupling_(coupling_of(model.sensor)),
      strain_coupling_(coupling_of(model.actuator)) {
  identity_ = {model.structure, parameter_hash(model),
               kernel_size(impl_) + stages_size(sensed_fix_, strain_fix_)};
}

Simulation::Output Simulation::step(double drive, double stress) noexcept {
  return gated_step(gate_, held_, last_, counts_, drive, stress,
                    [this](double x, double y) { return kernel_step(x, y); });
}

Simulation::Output Simulation::kernel_step(double drive, double stress) noexcept {
  Output out{};
  if (auto* affine = std::get_if<Affine>(&impl_)) {
    const ForwardModel::Output o = affine->step(drive, stress);
    out = {o.sensed, o.strain, SampleStatus::kOk};
  } else {
    const StressHysteresisForward::Output o = std::get<Vectorial>(impl_)->step(drive, stress);
    out = {o.sensed, o.strain, SampleStatus::kOk};
  }
  // The electrostriction term reads the sensed channel's response to the drive alone (D - d T);
  // a model without a sensor side has NaN there, and the term then has nothing.
  const double base_sensed = std::isnan(out.sensed) ? 0.0 : out.sensed - sensed_coupling_ * stress;
  if (sensed_fix_) {
    out.sensed = sensed_fix_->step({out.sensed, drive, stress, temperature_, base_sensed,
                                    out.sensed - sensed_coupling_ * stress});
  }
  if (strain_fix_) {
    out.strain = strain_fix_->step({out.strain, drive, stress, temperature_, base_sensed,
                                    out.strain - strain_coupling_ * stress});
  }
  return out;
}

SavedState Simulation::make_saved_state() const {
  return {identity_, std::vector<double>(identity_.state_size, 0.0)};
}

bool Simulation::save_state(SavedState& out) const noexcept {
  ConstStages stages{&sensed_fix_, &strain_fix_};
  return save_into(impl_, stages, identity_, out);
}

RestoreResult Simulation::restore_state(const SavedState& in) noexcept {
  Stages stages{&sensed_fix_, &strain_fix_};
  return restore_from(impl_, stages, identity_, in);
}

}  // namespace selfsense::models
