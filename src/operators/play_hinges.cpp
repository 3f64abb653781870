#include "selfsense/operators/play_hinges.hpp"

#include "selfsense/operators/parameter_error.hpp"

namespace selfsense::operators {

bool PlayHinges::is_valid(std::string* why) const {
  return check::all_non_negative("PlayHinges.thresholds", thresholds, why) &&
         check::all_finite("PlayHinges.levels", levels, why) &&
         check::all_finite("PlayHinges.weights", weights, why) &&
         check::same_size("PlayHinges.levels", levels.size(), "PlayHinges.thresholds",
                          thresholds.size(), why) &&
         check::same_size("PlayHinges.weights", weights.size(), "PlayHinges.thresholds",
                          thresholds.size(), why);
}

}  // namespace selfsense::operators
