// Fuzz target: model state files (daemon/model_state_file.hpp) from any text.
// Properties:
//  - a rejected file gives an io::YamlError "FILE:LINE: ..." and no other exception escapes;
//  - an accepted state round-trips: written (beside, then renamed) and read again, it has the
//    same identity and the same values (the model's and the health key's) bit for bit.
#include <cstdint>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include "fuzz_check.hpp"
#include "selfsense/daemon/model_state_file.hpp"
#include "selfsense/io/yaml_map.hpp"

// NOLINTNEXTLINE(readability-identifier-naming): the name libFuzzer calls.
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using selfsense::fuzz::require;
  static const selfsense::fuzz::ScratchFile in("state.yaml");
  static const selfsense::fuzz::ScratchFile out("copy.yaml");
  in.write(selfsense::fuzz::as_text(data, size));
  selfsense::models::SavedState state;
  std::vector<double> health;
  try {
    state = selfsense::daemon::read_model_state(in.path(), nullptr, &health);
  } catch (const selfsense::io::YamlError& e) {
    require(selfsense::fuzz::names_file_and_line(e.what(), in.path().string()),
            "a rejected model state names the file and line", e.what());
    return 0;
  } catch (const std::exception& e) {
    selfsense::fuzz::violated("only io::YamlError leaves the model state reader", e.what());
  }
  try {
    selfsense::daemon::write_model_state(out.path(), state, selfsense::daemon::StateOf::kPlain,
                                         health);
    std::vector<double> health_again;
    const selfsense::models::SavedState again =
        selfsense::daemon::read_model_state(out.path(), nullptr, &health_again);
    require(health_again.size() == health.size() &&
                (health.empty() || std::memcmp(health_again.data(), health.data(),
                                               health.size() * sizeof(double)) == 0),
            "an accepted state keeps its health values bit for bit");
    require(again.identity == state.identity, "an accepted state keeps its identity");
    require(again.values.size() == state.values.size() &&
                (state.values.empty() || std::memcmp(again.values.data(), state.values.data(),
                                                     state.values.size() * sizeof(double)) == 0),
            "an accepted state keeps its values bit for bit");
  } catch (const std::exception& e) {
    selfsense::fuzz::violated("an accepted state is written and read again", e.what());
  }
  return 0;
}
