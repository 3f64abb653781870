// Fuzz target: model files (model_io/model_yaml.hpp) from any text.
// Properties:
//  - a rejected file gives an io::YamlError "FILE:LINE: ..." (a YAML syntax error or a document
//    that is not a mapping names the line only; everything else also names the key path), and
//    no other exception escapes;
//  - an accepted model saves (model_to_string) to a text that loads again and saves to the same
//    text (the format promises bit-identical reloads).
#include <cstdint>
#include <exception>
#include <string>

#include "fuzz_check.hpp"
#include "selfsense/io/yaml_map.hpp"
#include "selfsense/model_io/model_yaml.hpp"

namespace {
constexpr const char* kSource = "fuzz-model.yaml";
}

// NOLINTNEXTLINE(readability-identifier-naming): the name libFuzzer calls.
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using selfsense::fuzz::require;
  const std::string text = selfsense::fuzz::as_text(data, size);
  selfsense::models::TransducerModel model;
  try {
    model = selfsense::models::model_from_string(text, kSource);
  } catch (const selfsense::io::YamlError& e) {
    require(selfsense::fuzz::names_file_and_line(e.what(), kSource),
            "a rejected model names the file and line", e.what());
    return 0;
  } catch (const std::exception& e) {
    selfsense::fuzz::violated("only io::YamlError leaves the model reader", e.what());
  }
  std::string saved;
  std::string saved_again;
  try {
    saved = selfsense::models::model_to_string(model);
    saved_again = selfsense::models::model_to_string(
        selfsense::models::model_from_string(saved, "saved.yaml"));
  } catch (const std::exception& e) {
    selfsense::fuzz::violated("an accepted model saves and loads again", e.what());
  }
  require(saved == saved_again, "a saved model reloads to the same file",
          saved + "\n---\n" + saved_again);
  return 0;
}
