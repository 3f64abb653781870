// Determinism: the same configuration and seed give byte-identical recordings; save/restore
// replays exactly.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "plant_test_util.hpp"
#include "selfsense/io/recording.hpp"
#include "selfsense/plant/excitation.hpp"
#include "selfsense/plant_io/plant_yaml.hpp"

namespace selfsense::plant {
namespace {

std::string recording_bytes(const PlantFile& file, const std::string& name) {
  const Excitation ex =
      make_excitation("noise", file.excitation, file.plant.sample_rate_hz, file.plant.seed);
  const auto out = simulate(file.plant, ex.inputs());
  io::Recording rec{};
  std::vector<double> t;
  std::vector<double> e;
  std::vector<double> d;
  std::vector<double> s;
  for (const auto& o : out) {
    t.push_back(o.t_s);
    e.push_back(o.e_meas_v_per_m);
    d.push_back(o.d_meas_c_per_m2);
    s.push_back(o.s);
  }
  rec.set_column("t", t);
  rec.set_column("E", e);
  rec.set_column("D", d);
  rec.set_column("S", s);
  const auto path = std::filesystem::temp_directory_path() / name;
  io::write_recording_csv(rec, path);
  std::ifstream in{path, std::ios::binary};
  std::ostringstream bytes;
  bytes << in.rdbuf();
  std::filesystem::remove(path);
  return bytes.str();
}

PlantFile noisy_file(std::uint64_t seed) {
  PlantFile file = load_plant_file(test::config_dir() / "all_effects.yaml");
  file.plant.seed = seed;
  file.plant.charge_amplifier.random_walk_c_per_sqrt_s = 1e-8;
  file.excitation.noise.duration_s = 0.05;
  return file;
}

TEST(PlantDeterminism, SameSeedGivesByteIdenticalCsv) {
  const std::string a = recording_bytes(noisy_file(3), "selfsense_plant_det_a.csv");
  const std::string b = recording_bytes(noisy_file(3), "selfsense_plant_det_b.csv");
  ASSERT_GT(a.size(), 1000U);
  EXPECT_TRUE(a == b);
}

TEST(PlantDeterminism, DifferentSeedGivesDifferentCsv) {
  const std::string a = recording_bytes(noisy_file(3), "selfsense_plant_det_c.csv");
  const std::string b = recording_bytes(noisy_file(4), "selfsense_plant_det_d.csv");
  EXPECT_FALSE(a == b);
}

TEST(PlantDeterminism, SaveAndRestoreReplayExactly) {
  const PlantFile file = noisy_file(5);
  Plant plant{file.plant};
  const Excitation ex = make_excitation("noise", file.excitation, file.plant.sample_rate_hz, 5);
  const auto in = ex.inputs();
  std::vector<StepOutput> first(in.size());
  std::vector<StepOutput> second(in.size());
  const std::size_t mid = in.size() / 2;
  for (std::size_t k = 0; k < mid; ++k)
    plant.step(in[k]);
  const Plant::State saved = plant.save();
  for (std::size_t k = mid; k < in.size(); ++k)
    first[k] = plant.step(in[k]);
  plant.restore(saved);
  for (std::size_t k = mid; k < in.size(); ++k)
    second[k] = plant.step(in[k]);
  for (std::size_t k = mid; k < in.size(); ++k) {
    ASSERT_EQ(first[k].d_meas_c_per_m2, second[k].d_meas_c_per_m2) << k;
    ASSERT_EQ(first[k].s, second[k].s) << k;
  }
  plant.reset();
  EXPECT_EQ(plant.step(in[0]).d_meas_c_per_m2, simulate(file.plant, in)[0].d_meas_c_per_m2);
}

}  // namespace
}  // namespace selfsense::plant
