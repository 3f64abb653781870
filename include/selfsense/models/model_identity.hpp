// Whose state is this? A saved model state (a flight-recorder dump, a hot swap, a restart)
// carries the identity of the model that wrote it, and restoring checks it, in release builds
// too: loading the play memory of one model into another gives plausible-looking nonsense.
//
// The hash is FNV-1a (64 bit) over the structure and every parameter that gives the state its
// meaning: operator thresholds, weights, couplings, offsets, histories and the vectorial model's
// coefficients, bit for bit. The sample time is left out on purpose: the state (play outputs,
// creep lag outputs) means the same at any loop rate, so a state saved at 1 kHz restores into
// the same model running at 20 kHz. The input ranges are left out too (they gate samples, they do
// not shape the memory).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "selfsense/models/transducer_model.hpp"

namespace selfsense::models {

struct ModelIdentity {
  Structure structure{Structure::kLinear};
  std::uint64_t parameter_hash{0};
  std::size_t state_size{0};  // doubles

  friend bool operator==(const ModelIdentity&, const ModelIdentity&) = default;
};

[[nodiscard]] std::uint64_t parameter_hash(const TransducerModel& model) noexcept;

// A state with the identity of the model that saved it. Sized once, outside the loop
// (Reconstruction::make_saved_state()); saving into it never allocates.
struct SavedState {
  ModelIdentity identity{};
  std::vector<double> values{};
};

enum class RestoreResult : std::uint8_t {
  kOk,
  kWrongModel,  // structure or parameter hash differ: the state belongs to another model
  kWrongSize,   // same model, but the buffer does not hold its state
};

}  // namespace selfsense::models
