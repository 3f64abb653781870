// The daemon's shipped model (config/models/sim.yaml: `preisach-creep` identified on the
// bench's identification recording, config/plant/daemon.yaml, the plant of test::daemon_plant),
// loaded once, so that the loop tests' figures are the product's.
#pragma once

#include <filesystem>

#include "selfsense/model_io/model_yaml.hpp"
#include "selfsense/models/transducer_model.hpp"

namespace selfsense::test {

inline const models::TransducerModel& bench_model() {
  static const models::TransducerModel m =
      models::load_model(std::filesystem::path(SELFSENSE_SOURCE_DIR) / "config/models/sim.yaml");
  return m;
}

}  // namespace selfsense::test
