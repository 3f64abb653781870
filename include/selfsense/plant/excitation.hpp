// Excitations for the plant: sequences of commanded field E (V/m), external force (N) and
// temperature (degC) at the plant's sample rate. Pure math; reading E(t) and the load from a
// CSV file belongs to the caller (the CLI), which fills an Excitation directly.
// Generation allocates (not real-time); the result feeds Plant::run sample by sample.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "selfsense/plant/plant.hpp"

namespace selfsense::plant {

// Levels held for hold_s each, starting from 0 V/m.
struct StepsConfig {
  std::vector<double> levels_v_per_m{0.5e6, 1.0e6, 2.0e6, 1.0e6, 0.0, 1.5e6, 0.5e6, 0.0};
  double hold_s{0.2};
};

// For every frequency, for every amplitude: `cycles` periods of offset + a sin(2 pi f t),
// entered and left by a ramp of ramp_s between 0 and the offset.
struct SinesConfig {
  std::vector<double> amplitudes_v_per_m{2.5e5, 5.0e5, 1.0e6};
  std::vector<double> frequencies_hz{2.0, 20.0, 200.0};
  double offset_v_per_m{1.0e6};
  int cycles{2};
  double ramp_s{0.02};
};

// offset + a r^n sin(2 pi f t) over `cycles` periods (r = decay_per_cycle): nested minor loops.
struct DecayingConfig {
  double amplitude_v_per_m{1.0e6};
  double offset_v_per_m{1.0e6};
  double frequency_hz{10.0};
  double decay_per_cycle{0.85};
  int cycles{20};
  double ramp_s{0.02};
};

// Seeded white Gaussian noise through two first-order low-passes at cutoff_hz, scaled to
// std_v_per_m, shifted by the offset and clipped to [min, max].
struct NoiseConfig {
  double duration_s{1.0};
  double cutoff_hz{50.0};
  double std_v_per_m{4.0e5};
  double offset_v_per_m{1.0e6};
  double min_v_per_m{0.0};
  double max_v_per_m{2.0e6};
};

// Minor loops of many sizes around many offsets, for identification: from min_v_per_m the
// field turns at seeded random extrema in [min, max], alternately up and down (the next
// extremum u^2 of the way to the limit, u uniform, so small loops are frequent and large
// ones occur), ramping at a random rate in [rate_min, rate_max] and holding a random time of
// up to hold_max_s at a third of the extrema (creep during holds).
struct LoopsConfig {
  double duration_s{60.0};
  double min_v_per_m{0.0};
  double max_v_per_m{2.0e6};
  double rate_min_v_per_m_s{0.2e6};
  double rate_max_v_per_m_s{4.0e6};
  double hold_max_s{2.0};
};

// External force: offset + amplitude sin(2 pi f t) (N); 0 amplitude for a constant force.
struct LoadConfig {
  double offset_n{0.0};
  double amplitude_n{0.0};
  double frequency_hz{1.0};
};

// Temperature: a linear ramp from start to end over the excitation.
struct TemperatureProfileConfig {
  double start_degc{25.0};
  double end_degc{25.0};
};

struct ExcitationConfig {
  StepsConfig steps{};
  SinesConfig sines{};
  DecayingConfig decaying{};
  NoiseConfig noise{};
  LoopsConfig loops{};
  LoadConfig load{};
  TemperatureProfileConfig temperature{};

  // As PlantConfig::is_valid, key paths under "excitation.".
  [[nodiscard]] bool is_valid(std::string* why) const;
};

struct Excitation {
  std::vector<double> e_v_per_m{};
  std::vector<double> force_n{};
  std::vector<double> temp_degc{};

  [[nodiscard]] std::size_t size() const noexcept { return e_v_per_m.size(); }
  // Plant inputs; force and temperature default to 0 N and 25 degC where empty.
  [[nodiscard]] std::vector<StepInput> inputs() const;
};

[[nodiscard]] std::vector<double> make_steps(const StepsConfig& config, double sample_rate_hz);
[[nodiscard]] std::vector<double> make_sines(const SinesConfig& config, double sample_rate_hz);
[[nodiscard]] std::vector<double> make_decaying(const DecayingConfig& config,
                                                double sample_rate_hz);
[[nodiscard]] std::vector<double> make_noise(const NoiseConfig& config, double sample_rate_hz,
                                             std::uint64_t seed);
[[nodiscard]] std::vector<double> make_loops(const LoopsConfig& config, double sample_rate_hz,
                                             std::uint64_t seed);

// kind: steps | sines | decaying | noise | loops | mix (the first four in that order) |
// identification (mix, then loops: what an identification recording should cover). Adds the
// load and the temperature profile. Throws std::invalid_argument for an unknown kind.
[[nodiscard]] Excitation make_excitation(const std::string& kind, const ExcitationConfig& config,
                                         double sample_rate_hz, std::uint64_t seed);
// Fills force and temperature of an excitation whose field is already set.
void apply_load_and_temperature(const ExcitationConfig& config, double sample_rate_hz,
                                Excitation& excitation);

}  // namespace selfsense::plant
