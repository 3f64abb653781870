// The model's memory on disk: written whole (beside the file, then renamed), read back bit for
// bit into the model that wrote it and refused by another; a cut or malformed file is named by
// file, line and key.
#include "selfsense/daemon/model_state_file.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "daemon/recording_support.hpp"
#include "selfsense/adaptation/adapted_reconstruction.hpp"
#include "selfsense/io/yaml_map.hpp"
#include "selfsense/model_io/model_yaml.hpp"
#include "selfsense/models/runtime_model.hpp"

namespace selfsense::daemon {
namespace {

std::string error_of(const std::filesystem::path& path) {
  try {
    static_cast<void>(read_model_state(path));
  } catch (const io::YamlError& e) {
    return e.what();
  }
  return "";
}

TEST(ModelStateFile, TheMemoryRoundTripsExactlyIntoItsOwnModelOnly) {
  const testing::ScratchDir dir("model-state");
  const std::filesystem::path source = SELFSENSE_SOURCE_DIR;
  const models::TransducerModel model =
      models::load_model(source / "config" / "models" / "sim.yaml");
  models::Reconstruction running(model, models::RuntimeOptions{1e-4});
  for (int k = 0; k < 20000; ++k) {  // a history far from the identification's start
    const double e = 1.6e6 * std::sin(0.0007 * k) * std::exp(-1e-4 * k) + 2e5;
    static_cast<void>(running.step(e, 0.03 + 1e-8 * e));
  }
  models::SavedState saved = running.make_saved_state();
  ASSERT_TRUE(running.save_state(saved));
  const std::filesystem::path path = dir.path() / "state.yaml";
  write_model_state(path, saved);
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "state.yaml.tmp"));

  const models::SavedState read = read_model_state(path);
  EXPECT_EQ(read.identity, saved.identity);
  EXPECT_EQ(read.values, saved.values);  // %.17g round-trips every double exactly
  models::Reconstruction restored(model, models::RuntimeOptions{1e-4});
  ASSERT_EQ(restored.restore_state(read), models::RestoreResult::kOk);
  for (int k = 0; k < 100; ++k) {
    const auto a = running.step(3e5, 0.031);
    const auto b = restored.step(3e5, 0.031);
    EXPECT_EQ(a.strain, b.strain);
    EXPECT_EQ(a.stress, b.stress);
  }

  models::TransducerModel other = model;
  other.actuator->offset += 1e-6;
  models::Reconstruction another(other, models::RuntimeOptions{1e-4});
  EXPECT_EQ(another.restore_state(read), models::RestoreResult::kWrongModel);
}

// The adapted reconstruction's state (kernel memory and learned drift) round-trips with its
// identity and the `reconstruction: adapted` key; a plain one reads as plain (also a file from
// before the key), and the adapted reconstruction refuses the plain state of the same model.
TEST(ModelStateFile, TheAdaptedStateSaysSoAndRoundTrips) {
  const testing::ScratchDir dir("model-state-adapted");
  const std::filesystem::path source = SELFSENSE_SOURCE_DIR;
  const models::TransducerModel model =
      models::load_model(source / "config" / "models" / "sim.yaml");
  adaptation::AdaptedReconstruction running(model, {}, 1e-4);
  models::Simulation plant(model, models::RuntimeOptions{1e-4});
  for (int k = 0; k < 20000; ++k) {  // the sensed D 1 % above the model's: a drift to learn
    const double e = 1.0e6 + 0.9e6 * std::sin(2.0 * std::numbers::pi * 5.0 * 1e-4 * k);
    static_cast<void>(running.step(e, 1.01 * plant.step(e, 0.0).sensed));
  }
  ASSERT_GT(running.estimator().updates(), 10U);
  models::SavedState saved = running.make_saved_state();
  ASSERT_TRUE(running.save_state(saved));
  const std::filesystem::path path = dir.path() / "adapted.yaml";
  write_model_state(path, saved, StateOf::kAdapted);
  StateOf of = StateOf::kPlain;
  const models::SavedState read = read_model_state(path, &of);
  EXPECT_EQ(of, StateOf::kAdapted);
  EXPECT_EQ(read.values, saved.values);
  adaptation::AdaptedReconstruction restored(model, {}, 1e-4);
  ASSERT_EQ(restored.restore_state(read), models::RestoreResult::kOk);
  EXPECT_EQ(restored.estimator().updates(), running.estimator().updates());
  EXPECT_EQ(restored.drift().permittivity, running.drift().permittivity);

  models::Reconstruction plain(model, models::RuntimeOptions{1e-4});
  const std::filesystem::path plain_path = dir.path() / "plain.yaml";
  write_model_state(plain_path, plain.make_saved_state());
  const models::SavedState plain_state = read_model_state(plain_path, &of);
  EXPECT_EQ(of, StateOf::kPlain);
  EXPECT_EQ(restored.restore_state(plain_state), models::RestoreResult::kWrongSize);
  EXPECT_EQ(plain.restore_state(read), models::RestoreResult::kWrongSize);

  std::string text = test::read_text(plain_path);
  text.replace(text.find("reconstruction: plain\n"), 22, "");  // a file from before the key
  test::write_text(plain_path, text);
  of = StateOf::kAdapted;
  static_cast<void>(read_model_state(plain_path, &of));
  EXPECT_EQ(of, StateOf::kPlain);
  std::string adapted_text = test::read_text(path);
  adapted_text.replace(adapted_text.find("adapted"), 7, "warm");
  test::write_text(plain_path, adapted_text);
  EXPECT_NE(error_of(plain_path).find("reconstruction: 'warm' is not one of plain, adapted"),
            std::string::npos)
      << error_of(plain_path);
}

TEST(ModelStateFile, ACutOrMalformedFileIsNamedByLineAndKey) {
  const testing::ScratchDir dir("model-state-bad");
  models::SavedState s;
  s.identity = {models::Structure::kHysteresisCreep, 0x0123456789abcdefULL, 3};
  s.values = {1.0, 0.5, 3.0};
  const std::filesystem::path path = dir.path() / "state.yaml";
  write_model_state(path, s);
  const std::string text = testing::read_text(path);
  const std::filesystem::path bad = dir.path() / "bad.yaml";

  testing::write_text(bad, text.substr(0, text.find("complete")));
  EXPECT_NE(error_of(bad).find("bad.yaml:"), std::string::npos) << error_of(bad);
  EXPECT_NE(error_of(bad).find("complete: missing at the end"), std::string::npos) << error_of(bad);
  // text with `from` (which it holds) replaced by `to`.
  const auto edited = [&](const std::string& from, const std::string& to) {
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return text.substr(0, at) + to + text.substr(at + from.size());
  };
  testing::write_text(bad, edited("0123456789abcdef", "not-a-hash"));
  EXPECT_NE(error_of(bad).find(":3: parameter_hash: expected 16 hexadecimal digits"),
            std::string::npos)
      << error_of(bad);
  testing::write_text(bad, edited(", 0.5,", ", x,"));
  EXPECT_NE(error_of(bad).find(":5: values[1]"), std::string::npos) << error_of(bad);
  testing::write_text(bad, edited("complete", "spare: 1\ncomplete"));
  EXPECT_NE(error_of(bad).find("spare"), std::string::npos) << error_of(bad);
}

TEST(ModelStateFile, TheHealthKeyRoundTripsAndIsOptional) {
  const testing::ScratchDir dir("model-state-health");
  models::SavedState s;
  s.identity = {models::Structure::kHysteresisCreep, 0x0123456789abcdefULL, 2};
  s.values = {1.0, 0.5};
  const std::vector<double> health = {std::numbers::pi, -1.0, 1e-300, 0.0};
  const std::filesystem::path path = dir.path() / "state.yaml";
  write_model_state(path, s, StateOf::kPlain, health);
  std::vector<double> read;
  EXPECT_EQ(read_model_state(path, nullptr, &read).values, s.values);
  EXPECT_EQ(read, health);     // %.17g: bit for bit
  write_model_state(path, s);  // no health: no key, and the reader says none
  EXPECT_EQ(testing::read_text(path).find("health"), std::string::npos);
  static_cast<void>(read_model_state(path, nullptr, &read));
  EXPECT_TRUE(read.empty());
  const std::vector<double> infinite = {1.0, std::numeric_limits<double>::infinity()};
  EXPECT_THROW(write_model_state(path, s, StateOf::kPlain, infinite), std::runtime_error);
  testing::write_text(path,
                      "selfsense_model_state: 1\nstructure: hysteresis-creep\n"
                      "parameter_hash: \"0123456789abcdef\"\nvalues: [1]\n"
                      "health: [1, .nan]\ncomplete: true\n");
  EXPECT_NE(error_of(path).find(":5: health[1]: expected a finite number"), std::string::npos)
      << error_of(path);
}

}  // namespace
}  // namespace selfsense::daemon
