// The running model's state on disk (models::SavedState): the hysteresis and creep memory of the
// self-sensing model, so that a restart goes on from the actuator's history instead of the
// identification recording's start. The daemon writes its `model_state` file at a clean stop
// and takes it (reads, then removes it) at the next start; restored only into the model that
// wrote it (identity check). The control socket's `state` request dumps the same format into
// the recorder's directory.
//
//   selfsense_model_state: 1
//   structure: hysteresis-creep
//   parameter_hash: "0123456789abcdef"   # models::parameter_hash, hexadecimal
//   reconstruction: adapted               # plain (models::Reconstruction; the default when
//                                         # absent, older files) or adapted
//                                         # (adaptation::AdaptedReconstruction: the kernel's
//                                         # memory, then the learned drift); the daemon takes a
//                                         # state only into the reconstruction that wrote it
//   values: [v0, v1, ...]                 # %.17g: the doubles round-trip exactly
//   health: [h0, h1, ...]                 # optional: the health estimate and its alarms
//                                         # (runtime::Loop::save_health_state), when health
//                                         # runs; absent in older files
//   complete: true                        # last: a file cut anywhere is refused
//
// Not real-time code: it allocates, does file I/O and throws.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string_view>
#include <vector>

#include "selfsense/models/model_identity.hpp"

namespace selfsense::daemon {

// Which reconstruction wrote the state (the `reconstruction` key).
enum class StateOf : std::uint8_t { kPlain, kAdapted };
[[nodiscard]] std::string_view to_string(StateOf of) noexcept;

// Writes beside `path` and renames over it, so a reader never sees half a file. Throws
// std::runtime_error naming the path (also for a value that is not finite).
// An empty `health` writes no health key.
void write_model_state(const std::filesystem::path& path, const models::SavedState& state,
                       StateOf of = StateOf::kPlain, std::span<const double> health = {});

// Throws io::YamlError ("file:line: key: ...") on a malformed or cut file, a hash that is not
// 16 hexadecimal digits or a value that is not finite.
// *of (when not null) gets the `reconstruction` key (kPlain when absent); *health (when not
// null) the `health` values (empty when absent).
[[nodiscard]] models::SavedState read_model_state(const std::filesystem::path& path,
                                                  StateOf* of = nullptr,
                                                  std::vector<double>* health = nullptr);

}  // namespace selfsense::daemon
