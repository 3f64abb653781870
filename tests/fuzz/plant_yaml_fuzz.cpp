// Fuzz target: plant configurations (plant_io/plant_yaml.hpp) from any text.
// Properties:
//  - a rejected file gives an io::YamlError "FILE:LINE: ..." and no other exception escapes;
//  - an accepted configuration builds the simulated transducer without an exception (loading
//    validated everything the plant checks) and the plant runs a few samples.
#include <cstdint>
#include <exception>
#include <string>

#include "fuzz_check.hpp"
#include "selfsense/io/yaml_map.hpp"
#include "selfsense/plant/plant.hpp"
#include "selfsense/plant_io/plant_yaml.hpp"

namespace {
constexpr const char* kSource = "fuzz-plant.yaml";
constexpr int kSteps = 16;
}  // namespace

// NOLINTNEXTLINE(readability-identifier-naming): the name libFuzzer calls.
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using selfsense::fuzz::require;
  const std::string text = selfsense::fuzz::as_text(data, size);
  selfsense::plant::PlantFile file;
  try {
    file = selfsense::plant::parse_plant_yaml(text, kSource);
  } catch (const selfsense::io::YamlError& e) {
    require(selfsense::fuzz::names_file_and_line(e.what(), kSource),
            "a rejected plant configuration names the file and line", e.what());
    return 0;
  } catch (const std::exception& e) {
    selfsense::fuzz::violated("only io::YamlError leaves the plant reader", e.what());
  }
  try {
    selfsense::plant::Plant plant(file.plant);
    for (int k = 0; k < kSteps; ++k)
      static_cast<void>(plant.step(selfsense::plant::StepInput{}));
  } catch (const std::exception& e) {
    selfsense::fuzz::violated("an accepted plant configuration builds a plant", e.what());
  }
  return 0;
}
