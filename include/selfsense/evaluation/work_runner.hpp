// The identification's WorkRunner (identification/transducer_fit.hpp) on threads: for the
// programs that may run threads (`selfsense identify`); the pure math runs none.
#pragma once

#include <functional>
#include <span>

namespace selfsense::evaluation {

// Runs the first piece on the calling thread and every other piece on a thread of its own
// beside it: on a machine with two free cores an identification's two side fits overlap.
// Returns once every piece has ended; an exception a piece threw is rethrown then (the first
// piece's before the others', the others' in order).
void run_on_threads(std::span<const std::function<void()>> work);

}  // namespace selfsense::evaluation
