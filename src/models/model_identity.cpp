#include "selfsense/models/model_identity.hpp"

#include <bit>
#include <cstdint>
#include <iterator>
#include <span>

namespace selfsense::models {
namespace {

// FNV-1a, 64 bit, fed with the bit patterns of the parameters.
class Fnv1a {
 public:
  void add(std::uint64_t word) noexcept {
    for (int byte = 0; byte < 8; ++byte) {
      hash_ ^= (word >> (8 * byte)) & 0xffU;
      hash_ *= kPrime;
    }
  }
  void add(double x) noexcept { add(std::bit_cast<std::uint64_t>(x)); }
  // The length first, so [1, 2] + [] and [1] + [2] hash differently.
  void add(std::span<const double> xs) noexcept {
    add(static_cast<std::uint64_t>(xs.size()));
    for (const double x : xs)
      add(x);
  }
  [[nodiscard]] std::uint64_t value() const noexcept { return hash_; }

 private:
  static constexpr std::uint64_t kPrime = 1099511628211ULL;
  std::uint64_t hash_{14695981039346656037ULL};
};

void add_side(Fnv1a& h, const std::optional<SideModel>& side) noexcept {
  h.add(static_cast<std::uint64_t>(side.has_value()));
  if (!side) return;
  const auto& op = side->op;
  h.add(op.hysteresis.linear_weight);
  h.add(op.hysteresis.thresholds);
  h.add(op.hysteresis.weights);
  h.add(op.superposition.linear_weight);
  h.add(op.superposition.upper_thresholds);
  h.add(op.superposition.upper_weights);
  h.add(op.superposition.lower_thresholds);
  h.add(op.superposition.lower_weights);
  h.add(op.creep.thresholds);
  h.add(op.creep.eigenvalues);
  h.add(op.creep.weights);
  if (!op.hinges.empty()) {  // models without hinges keep the identity they had
    h.add(op.hinges.thresholds);
    h.add(op.hinges.levels);
    h.add(op.hinges.weights);
  }
  h.add(side->linear_gains);
  h.add(side->offset);
  h.add(side->quadratic);
  h.add(side->history);
}

void add_correction(Fnv1a& h, const std::optional<ChannelCorrection>& c) noexcept {
  h.add(static_cast<std::uint64_t>(c.has_value()));
  if (!c) return;
  for (const double x :
       {c->gain, c->offset, c->temperature_reference_degc, c->temperature_gain_per_k,
        c->temperature_offset_per_k, c->temperature_drive_per_k, c->stress_gain_per_pa,
        c->stress_quadratic_per_pa2, c->drive_quadratic, c->drive_cubic, c->sensed_quadratic,
        c->dynamics_frequency_hz, c->dynamics_damping, c->leakage_tau_s, c->delay_s}) {
    h.add(x);
  }
  h.add(c->creep_eigenvalues);
  h.add(c->creep_weights);
  if (!c->hysteresis_thresholds.empty() || !c->hinge_thresholds.empty()) {
    h.add(c->hysteresis_thresholds);  // corrections without plays keep the identity they had
    h.add(c->hysteresis_weights);
    h.add(c->hinge_thresholds);
    h.add(c->hinge_levels);
    h.add(c->hinge_weights);
  }
  if (c->drive_linear != 0.0) h.add(c->drive_linear);  // likewise for corrections without it
  // Terms added later: hashed only when used, so older corrections keep their identity.
  // Each tagged by its place, so one value in another of them is another identity.
  const double later[] = {
      c->temperature_gain_per_k2,  c->temperature_offset_per_k2, c->drive_integral_per_s,
      c->temperature_drive_per_k2, c->temperature_stress_per_k,  c->temperature_stress_per_k2,
      c->stress_drive_per_pa,      c->stress_linear_per_pa,      c->dynamics_direct,
      c->dynamics2_frequency_hz,   c->dynamics2_damping,         c->dynamics2_share};
  for (std::uint64_t i = 0; i < std::size(later); ++i) {
    if (later[i] == 0.0) continue;
    h.add(std::uint64_t{0x5e1f0000} + i);
    h.add(later[i]);
  }
  if (!c->drive_creep_eigenvalues.empty()) {
    h.add(c->drive_creep_eigenvalues);
    h.add(c->drive_creep_weights);
  }
}

void add_vectorial_side(Fnv1a& h, const std::optional<StressHysteresisSide>& side) noexcept {
  h.add(static_cast<std::uint64_t>(side.has_value()));
  if (!side) return;
  h.add(side->base);
  h.add(side->stress);
  h.add(side->linear);
  h.add(side->quadratic);
  h.add(side->offset);
}

}  // namespace

std::uint64_t parameter_hash(const TransducerModel& model) noexcept {
  Fnv1a h;
  h.add(static_cast<std::uint64_t>(model.structure));
  add_side(h, model.sensor);
  add_side(h, model.actuator);
  h.add(static_cast<std::uint64_t>(model.vectorial.has_value()));
  if (model.vectorial) {
    const StressHysteresisModel& v = *model.vectorial;
    h.add(v.basis.thresholds);
    h.add(v.basis.eigenvalues);
    for (const std::size_t r : v.basis.creep_rows)
      h.add(static_cast<std::uint64_t>(r));
    h.add(v.history);
    h.add(v.stress_min);
    h.add(v.stress_max);
    add_vectorial_side(h, v.sensor);
    add_vectorial_side(h, v.actuator);
  }
  add_correction(h, model.sensed_correction);
  add_correction(h, model.strain_correction);
  return h.value();
}

}  // namespace selfsense::models
