// A run of the simulated stack as files (`selfsense plant`, docs/recording-format.md): the
// excitation read from a recording, and the run written as a recording.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "selfsense/io/recording.hpp"
#include "selfsense/plant/config.hpp"
#include "selfsense/plant/excitation.hpp"
#include "selfsense/plant/plant.hpp"

namespace selfsense::plant {

// E [V/m] and optionally F_ext [N] (external force on the stack; F in our recordings is the stack
// force T A) and temp [degC] from a recording with t, linearly interpolated onto the grid of
// `sample_rate_hz`; the load and temperature of `config` where the recording has none. Throws
// io::RecordingError (or std::runtime_error for fewer than two rows) naming the file.
[[nodiscard]] Excitation read_excitation_csv(const std::filesystem::path& path,
                                             const ExcitationConfig& config, double sample_rate_hz);

// The recording of a run: measured t, E, D; the plant's true S and T as reference columns; temp
// where the excitation's temperature varies or the stack heats itself; the true terminal values
// (u, q, x, F), E_true, D_true and diagnostic columns (q_amp, p, status, latency_s where there is
// latency). Recordings hold finite numbers only: a NaN fault keeps its status bit and repeats the
// previous delivered value. `heading` is the first comment line.
[[nodiscard]] io::Recording plant_recording(const PlantConfig& config, const Excitation& excitation,
                                            std::vector<StepOutput> outputs,
                                            const std::string& heading);

}  // namespace selfsense::plant
