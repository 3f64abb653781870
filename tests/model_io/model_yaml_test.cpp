#include "selfsense/model_io/model_yaml.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "selfsense/identification/stress_hysteresis_fit.hpp"
#include "selfsense/io/yaml_map.hpp"
#include "selfsense/models/model_identity.hpp"
#include "support/transducer_data.hpp"

namespace selfsense::models {
namespace {

using identification::fit_stress_hysteresis;

void expect_error(const std::string& text, const std::string& fragment) {
  try {
    static_cast<void>(model_from_string(text, "M.yaml"));
    FAIL() << "accepted; expected an error containing " << fragment;
  } catch (const io::YamlError& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

const std::string kMinimal = R"(selfsense_model: 1
structure: hysteresis
sample_time_s: 0.001
sensor:
  coupling: 3.0e-10
  hysteresis:
    linear_weight: 4.0e-8
    thresholds: [1.0e5, 2.0e5]
    weights: [1.0e-9, 2.0e-9]
)";

TEST(ModelYaml, RoundTripIsBitIdentical) {
  TransducerModel m = test::typical_transducer(1e-4);
  m.geometry = Geometry{60e-6, 25e-6, 167, 10e-3, 25e-6};
  const std::string text = model_to_string(m, "S: {nrmse: 0.001}");
  const TransducerModel back = model_from_string(text);
  EXPECT_EQ(model_to_string(back, "S: {nrmse: 0.001}"), text);
  EXPECT_EQ(back.sensor->op.hysteresis.weights, m.sensor->op.hysteresis.weights);
  EXPECT_EQ(back.actuator->op.creep.weights, m.actuator->op.creep.weights);
  EXPECT_EQ(back.sensor->history, m.sensor->history);
  EXPECT_EQ(back.geometry->layers, 167.0);
  EXPECT_EQ(back.structure, Structure::kHysteresisCreep);
}

TEST(ModelYaml, HingesRoundTripAndAreValidatedByKey) {
  TransducerModel m = test::typical_transducer(1e-4);
  m.structure = Structure::kPreisachCreep;
  m.sensor->op.hinges = {{0.0, 2e5}, {1.0e6, 0.8e6}, {1e-9, -2e-10}};
  const std::string text = model_to_string(m, "");
  const TransducerModel back = model_from_string(text);
  EXPECT_EQ(model_to_string(back, ""), text);
  EXPECT_EQ(back.structure, Structure::kPreisachCreep);
  EXPECT_EQ(back.sensor->op.hinges.levels, m.sensor->op.hinges.levels);
  EXPECT_EQ(back.sensor->op.hinges.weights, m.sensor->op.hinges.weights);
  EXPECT_TRUE(back.actuator->op.hinges.empty());
  expect_error(kMinimal +
                   "  hinges:\n    thresholds: [-1.0]\n    levels: [0.0]\n"
                   "    weights: [1.0]\n",
               "sensor.hinges.thresholds[0]");
  expect_error(kMinimal +
                   "  hinges:\n    thresholds: [1.0]\n    levels: [0.0, 1.0]\n"
                   "    weights: [1.0]\n",
               "sensor.hinges.levels");
}

TEST(ModelYaml, VectorialModelRoundTrips) {
  const test::TransducerData d = test::transducer_data(test::typical_transducer(1e-3), 3000, 0, 4);
  TransducerModel m;
  m.structure = Structure::kStressHysteresis;
  m.sample_time = 1e-3;
  m.vectorial = fit_stress_hysteresis(d.e, d.t, d.d, d.s, 1e-3, 6);
  const std::string text = model_to_string(m);
  const TransducerModel back = model_from_string(text);
  ASSERT_TRUE(back.vectorial.has_value());
  EXPECT_EQ(back.vectorial->sensor->stress, m.vectorial->sensor->stress);
  EXPECT_EQ(back.vectorial->basis.thresholds, m.vectorial->basis.thresholds);
  EXPECT_EQ(model_to_string(back), text);
  std::string broken = text;
  broken.replace(broken.find("stress_range: ["), 15, "stress_range: [1, ");
  expect_error(broken, "stress_range");
}

// Completed by a plain side where its vectorial section has none (models/stress_sides.hpp):
// both come back, and a plain side where the vectorial section has one is refused by key.
TEST(ModelYaml, VectorialModelCompletedByAPlainSideRoundTrips) {
  const test::TransducerData d = test::transducer_data(test::typical_transducer(1e-3), 3000, 0, 4);
  TransducerModel m;
  m.structure = Structure::kStressHysteresis;
  m.sample_time = 1e-3;
  m.vectorial = fit_stress_hysteresis(d.e, d.t, d.d, d.s, 1e-3, 6);
  m.vectorial->sensor.reset();
  m.sensor = test::typical_transducer(1e-3).sensor;
  const std::string text = model_to_string(m);
  const TransducerModel back = model_from_string(text);
  ASSERT_TRUE(back.vectorial.has_value());
  EXPECT_FALSE(back.vectorial->sensor.has_value());
  ASSERT_TRUE(back.sensor.has_value());
  EXPECT_EQ(back.sensor->op.hysteresis.weights, m.sensor->op.hysteresis.weights);
  EXPECT_EQ(parameter_hash(back), parameter_hash(m));
  EXPECT_EQ(model_to_string(back), text);
  TransducerModel twice = m;
  twice.actuator = test::typical_transducer(1e-3).actuator;
  std::string plain_actuator = model_to_string(twice);
  expect_error(plain_actuator, "actuator: the vectorial section has this side already");
}

// With creep lags among its columns: the rows and eigenvalues come back, the gains follow from
// them at the model's rate, and rows beyond the plays are refused by key.
TEST(ModelYaml, VectorialModelWithCreepRoundTrips) {
  const test::TransducerData d = test::transducer_data(test::typical_transducer(1e-3), 3000, 0, 4);
  TransducerModel m;
  m.structure = Structure::kStressHysteresis;
  m.sample_time = 1e-3;
  m.vectorial = fit_stress_hysteresis(d.e, d.t, d.d, d.s, 1e-3, 6, {3, 1, 0.0, 0.0});
  ASSERT_EQ(m.vectorial->basis.creep(), 6U);
  ASSERT_EQ(m.vectorial->sensor->base.size(), 7U + 6U);
  const std::string text = model_to_string(m);
  const TransducerModel back = model_from_string(text);
  ASSERT_TRUE(back.vectorial.has_value());
  EXPECT_EQ(back.vectorial->basis.creep_rows, m.vectorial->basis.creep_rows);
  EXPECT_EQ(back.vectorial->basis.eigenvalues, m.vectorial->basis.eigenvalues);
  EXPECT_EQ(back.vectorial->sensor->base, m.vectorial->sensor->base);
  EXPECT_EQ(model_to_string(back), text);
  std::string broken = text;
  broken.replace(broken.find("rows: [0, "), 10, "rows: [0, 9");
  expect_error(broken, "vectorial.creep.rows");
}

// The temperature coefficients (models/temperature_coefficients.hpp) come back bit-identical
// and do not change the parameter hash; a polynomial that is not two numbers, a missing side
// and a model with one side are refused by key; the increments' pair is optional.
TEST(ModelYaml, TemperatureCoefficientsRoundTripAndAreCheckedByKey) {
  TransducerModel m = test::typical_transducer(1e-4);
  TemperatureCoefficients t;
  t.reference_degc = 25.5;
  t.sensor = {{3.9e-3, -1.25e-6}, {-4.1e-3, 2.0e-6}, {2.1e-3, 0.0}};
  t.actuator = {{2.0e-3, 1.0e-7}, {-3.9e-3, 0.0}, {5.2e-4, -3.0e-9}};
  m.temperature = t;
  const std::string text = model_to_string(m);
  const TransducerModel back = model_from_string(text);
  ASSERT_TRUE(back.temperature.has_value());
  EXPECT_EQ(*back.temperature, t);
  EXPECT_EQ(model_to_string(back), text);
  EXPECT_DOUBLE_EQ(t.sensor.linear.scale(10.0), 1.0 + 3.9e-2 - 1.25e-4);
  std::string pair = text;
  pair.replace(pair.find("loop: [-0.0041"), 14, "loop: [-0.0041, 1");
  expect_error(pair, "temperature.sensor.loop: expected [per_k, per_k2]");
  std::string side = text;
  side.replace(side.find("  actuator:\n    linear"), 11, "  actuatorx:");
  expect_error(side, "temperature");
  expect_error(kMinimal + "temperature:\n  reference_degc: 25\n", "temperature: needs a field");
  // The increments' drift (optional): written when fitted, read back bit-identical.
  t.increments = {3.8375e-3, -4.6e-3};
  m.temperature = t;
  const std::string with_increments = model_to_string(m);
  const std::size_t at = with_increments.find("increments: [0.00383750");
  ASSERT_NE(at, std::string::npos);
  EXPECT_EQ(*model_from_string(with_increments).temperature, t);
  std::string one = with_increments;
  one.replace(at, one.find(',', at) + 2 - at, "increments: [");
  expect_error(one, "temperature.increments: expected [linear_per_k, loop_per_k]");
}

TEST(ModelYaml, MinimalModelLoads) {
  const TransducerModel m = model_from_string(kMinimal);
  EXPECT_FALSE(m.actuator.has_value());
  EXPECT_DOUBLE_EQ(m.sensor->linear_gains.at(0), 3e-10);
  EXPECT_TRUE(m.sensor->op.creep.eigenvalues.empty());
}

TEST(ModelYaml, ErrorsNameFileLineAndKey) {
  expect_error(kMinimal + "bogus: 1\n", "M.yaml:10: bogus");
  std::string bad_weight = kMinimal;
  bad_weight.replace(bad_weight.find("[1.0e-9, 2.0e-9]"), 16, "[-5.0e-8, 2.0e-9]");
  expect_error(bad_weight, "sensor.hysteresis.weights[0]: partial sum");
  std::string unsorted = kMinimal;
  unsorted.replace(unsorted.find("[1.0e5, 2.0e5]"), 14, "[2.0e5, 1.0e5]");
  expect_error(unsorted, "sensor.hysteresis.thresholds[1]");
  std::string version = kMinimal;
  version.replace(version.find("selfsense_model: 1"), 18, "selfsense_model: 7");
  expect_error(version, "M.yaml:1: selfsense_model: format version 7");
  std::string structure = kMinimal;
  structure.replace(structure.find("hysteresis\n"), 10, "preisach");
  expect_error(structure, "structure: 'preisach' is not one of linear");
  expect_error("selfsense_model: 1\nstructure: linear\nsample_time_s: 0.001\n",
               "needs a sensor or an actuator side");
  expect_error(R"(selfsense_model: 1
structure: linear
sample_time_s: 0.001
sensor:
  coupling: 1.0
)",
               "sensor.hysteresis: required key is missing");
}

// A file cut short anywhere (copied over the old one while the daemon reloads, a copy that was
// interrupted) is refused: without the end marker a cut inside a number or after a line of a
// list leaves valid YAML and a different model.
TEST(ModelYaml, EveryPrefixOfASavedModelIsRefused) {
  TransducerModel m = test::typical_transducer(1e-4);
  const std::string text = model_to_string(m, "S: {nrmse: 0.001}");
  ASSERT_EQ(text.substr(text.size() - 15), "complete: true\n");
  std::size_t accepted = 0;
  for (std::size_t n = 0; n + 1 < text.size(); ++n) {  // the last byte is the final newline
    try {
      static_cast<void>(model_from_string(text.substr(0, n), "M.yaml"));
      ++accepted;
      ADD_FAILURE() << "a prefix of " << n << " of " << text.size() << " bytes loaded";
    } catch (const io::YamlError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("M.yaml", 0), 0U) << e.what();
    }
  }
  EXPECT_EQ(accepted, 0U);
  EXPECT_NO_THROW(static_cast<void>(model_from_string(text.substr(0, text.size() - 1))));
}

TEST(ModelYaml, TheEndMarkerIsRequiredFromFormatTwoAndMustBeLast) {
  const std::string v2 = "selfsense_model: 2" + kMinimal.substr(kMinimal.find('\n'));
  expect_error(v2, "complete: missing");
  EXPECT_NO_THROW(static_cast<void>(model_from_string(v2 + "complete: true\n")));
  expect_error(v2 + "complete: false\n", "complete: must be true");
  std::string early = v2;
  early.insert(early.find("sample_time_s"), "complete: true\n");
  expect_error(early, "complete: must be the file's last key");
  EXPECT_NO_THROW(static_cast<void>(model_from_string(kMinimal)));  // format 1: no marker
  expect_error("selfsense_model: 3" + kMinimal.substr(kMinimal.find('\n')),
               "format version 3 is not supported (this build reads 1 to 2)");
}

// save_model replaces the file in one rename: the old content or the new, nothing between,
// and no temporary file left behind.
TEST(ModelYaml, SaveReplacesTheFileWhole) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("selfsense-model-save-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::filesystem::path path = dir / "m.yaml";
  {
    std::ofstream old(path);
    old << "an old file, longer than nothing\n";
  }
  const TransducerModel m = test::typical_transducer(1e-4);
  save_model(m, path, "S: {nrmse: 0.001}");
  EXPECT_EQ(model_to_string(load_model(path)), model_to_string(m));
  std::size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    static_cast<void>(entry);
    ++files;
  }
  EXPECT_EQ(files, 1U);
  EXPECT_THROW(save_model(m, dir / "missing" / "m.yaml"), std::runtime_error);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace selfsense::models
