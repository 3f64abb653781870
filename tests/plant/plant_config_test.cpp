// Configuration: validation names the key path; the YAML loader is strict; every example loads
// and dissipates energy around its D-E loop.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "plant_test_util.hpp"
#include "selfsense/io/yaml_map.hpp"
#include "selfsense/plant/excitation.hpp"
#include "selfsense/plant_io/plant_yaml.hpp"

namespace selfsense::plant {
namespace {

std::string why_invalid(const PlantConfig& c) {
  std::string why;
  EXPECT_FALSE(c.is_valid(&why));
  return why;
}

std::string load_error(const std::string& yaml) {
  try {
    static_cast<void>(parse_plant_yaml(yaml, "P.yaml"));
  } catch (const io::YamlError& e) {
    return e.what();
  }
  ADD_FAILURE() << "accepted:\n" << yaml;
  return {};
}

TEST(PlantConfig, DefaultsAreValid) {
  std::string why;
  EXPECT_TRUE(PlantConfig{}.is_valid(&why)) << why;
  EXPECT_TRUE(ExcitationConfig{}.is_valid(&why)) << why;
}

TEST(PlantConfig, ResonanceAboveNyquistNamesTheKey) {
  PlantConfig c{};
  c.mechanics.enabled = true;
  c.mechanics.resonance_hz = 80000.0;
  EXPECT_EQ(why_invalid(c),
            "plant.mechanics.resonance_hz: 80000 is above the Nyquist frequency 50000 of "
            "sample_rate_hz");
}

TEST(PlantConfig, NegativeCapacitanceIsRejected) {
  PlantConfig c{};
  c.material.permittivity_f_per_m = -2e-8;
  EXPECT_NE(why_invalid(c).find("plant.material.permittivity_f_per_m: -2e-08"), std::string::npos);
}

TEST(PlantConfig, OtherConstraintsNameTheirKeys) {
  PlantConfig c{};
  c.creep.tau_s[2] = -1.0;
  EXPECT_NE(why_invalid(c).find("plant.creep.tau_s[2]"), std::string::npos);
  c = PlantConfig{};
  c.creep.s_weights.pop_back();
  EXPECT_NE(why_invalid(c).find("plant.creep.s_weights"), std::string::npos);
  c = PlantConfig{};
  c.sensors.d.adc.max = -1.0;
  EXPECT_NE(why_invalid(c).find("plant.sensors.d.adc.max"), std::string::npos);
  c = PlantConfig{};
  c.sensors.e.delay_samples = 1000;
  EXPECT_NE(why_invalid(c).find("plant.sensors.e.delay_samples"), std::string::npos);
  c = PlantConfig{};
  c.hysteresis.asymmetry = 1.5;
  EXPECT_NE(why_invalid(c).find("plant.hysteresis.asymmetry"), std::string::npos);
  c = PlantConfig{};
  c.permittivity.enabled = true;
  c.permittivity.linear_coefficient = -3.0;
  EXPECT_NE(why_invalid(c).find("plant.permittivity"), std::string::npos);
  c = PlantConfig{};
  c.faults.push_back(FaultEntry{FaultKind::late_sample, Channel::both, 0.1, 0.0, 0.0});
  EXPECT_NE(why_invalid(c).find("plant.faults[0].late_by_s"), std::string::npos);
  c = PlantConfig{};
  c.amplifier.voltage_min_v = 10.0;  // the plant starts at 0 V
  EXPECT_NE(why_invalid(c).find("plant.amplifier.voltage_min_v: 10"), std::string::npos);
  c = PlantConfig{};
  c.charge_amplifier.leakage_tau_s = std::nan("");
  EXPECT_NE(why_invalid(c).find("plant.charge_amplifier.leakage_tau_s: nan"), std::string::npos);
}

TEST(ExcitationConfig, NonFiniteValuesNameTheirKeys) {
  ExcitationConfig x{};
  x.sines.ramp_s = std::numeric_limits<double>::infinity();
  std::string why;
  EXPECT_FALSE(x.is_valid(&why));
  EXPECT_NE(why.find("excitation.sines.ramp_s: inf"), std::string::npos) << why;
  x = ExcitationConfig{};
  x.noise.min_v_per_m = std::nan("");
  EXPECT_FALSE(x.is_valid(&why));
  EXPECT_NE(why.find("excitation.noise.min_v_per_m"), std::string::npos) << why;
}

TEST(ExcitationConfig, LoopsTurnInsideTheirRangeAtManySizesAndOffsets) {
  LoopsConfig c{};
  c.duration_s = 60.0;
  const std::vector<double> e = make_loops(c, 1000.0, 7);
  ASSERT_EQ(e.size(), 60000U);
  std::vector<double> turns;
  for (std::size_t k = 1; k + 1 < e.size(); ++k) {
    ASSERT_GE(e[k], c.min_v_per_m);
    ASSERT_LE(e[k], c.max_v_per_m);
    const double in = e[k] - e[k - 1];
    const double out = e[k + 1] - e[k];
    if (in * out < 0.0) turns.push_back(e[k]);
  }
  // Many reversals, at low, middle and high field, of small and large size.
  ASSERT_GT(turns.size(), 40U);
  const auto count_if = [&](auto pred) { return std::count_if(turns.begin(), turns.end(), pred); };
  EXPECT_GT(count_if([](double v) { return v < 0.6e6; }), 3);
  EXPECT_GT(count_if([](double v) { return v > 0.7e6 && v < 1.3e6; }), 3);
  EXPECT_GT(count_if([](double v) { return v > 1.4e6; }), 3);
  std::size_t small = 0;
  std::size_t large = 0;
  for (std::size_t i = 1; i < turns.size(); ++i) {
    const double size = std::abs(turns[i] - turns[i - 1]);
    small += size < 0.2e6 ? 1U : 0U;
    large += size > 0.8e6 ? 1U : 0U;
  }
  EXPECT_GT(small, 3U);
  EXPECT_GT(large, 3U);
  // Seeded: the same seed, the same field.
  EXPECT_EQ(make_loops(c, 1000.0, 7), e);
  c.rate_max_v_per_m_s = 0.1e6;
  std::string why;
  ExcitationConfig x{};
  x.loops = c;
  EXPECT_FALSE(x.is_valid(&why));
  EXPECT_NE(why.find("excitation.loops.rate_max_v_per_m_s"), std::string::npos) << why;
}

TEST(PlantYaml, UnknownKeyNamesPathAndLine) {
  const std::string msg = load_error("plant:\n  creep:\n    enabled: true\n    tua_s: [1]\n");
  EXPECT_EQ(msg, "P.yaml:4: plant.creep.tua_s: unknown key");
}

TEST(PlantYaml, UnknownTopLevelSectionIsAnError) {
  EXPECT_EQ(load_error("plant: {}\nplnat: {}\n"), "P.yaml:2: plnat: unknown key");
}

TEST(PlantYaml, WrongTypeNamesTheKey) {
  EXPECT_EQ(load_error("plant:\n  mechanics:\n    resonance_hz: fast\n"),
            "P.yaml:3: plant.mechanics.resonance_hz: expected a number, got 'fast'");
  EXPECT_EQ(load_error("plant:\n  geometry: {layers: 1.5}\n"),
            "P.yaml:2: plant.geometry.layers: expected an integer, got '1.5'");
}

TEST(PlantYaml, InvalidValueNamesKeyAndLine) {
  const std::string msg = load_error(
      "plant:\n  sample_rate_hz: 100000\n  mechanics:\n    enabled: true\n"
      "    resonance_hz: 80000\n");
  EXPECT_EQ(msg,
            "P.yaml:5: plant.mechanics.resonance_hz: 80000 is above the Nyquist frequency 50000 "
            "of sample_rate_hz");
  EXPECT_NE(load_error("plant:\n  material: {permittivity_f_per_m: -1.0e-8}\n")
                .find("P.yaml:2: plant.material.permittivity_f_per_m"),
            std::string::npos);
}

TEST(PlantYaml, BadFaultKindListsTheChoices) {
  const std::string msg = load_error("plant:\n  faults:\n    - {kind: gremlin, start_s: 1}\n");
  EXPECT_NE(msg.find("P.yaml:3: plant.faults[0].kind: 'gremlin' is not one of: stuck_adc"),
            std::string::npos);
}

TEST(PlantYaml, ExcitationSectionIsStrictToo) {
  EXPECT_EQ(load_error("plant: {}\nexcitation:\n  sines: {cycles: 0}\n"),
            "P.yaml:3: excitation.sines.cycles: 0 must be >= 1");
  EXPECT_EQ(load_error("plant: {}\nexcitation:\n  steps: {hold: 1}\n"),
            "P.yaml:3: excitation.steps.hold: unknown key");
}

TEST(PlantYaml, ReadsEveryValueIntoTheStructs) {
  const PlantFile f = parse_plant_yaml(
      "plant:\n  seed: 42\n  creep: {enabled: true, tau_s: [1, 2], s_weights: [0.1, 0.2],"
      " d_weights: [0, 0]}\n  sensors: {d: {adc: {enabled: true, bits: 12}}}\n"
      "  faults:\n    - {kind: stuck_adc, channel: e, start_s: 0.5, duration_s: 0.1}\n"
      "excitation:\n  temperature: {end_degc: 60}\n  loops: {duration_s: 12, hold_max_s: 0.5}\n");
  EXPECT_EQ(f.plant.seed, 42U);
  EXPECT_TRUE(f.plant.creep.enabled);
  EXPECT_EQ(f.plant.creep.tau_s, (std::vector<double>{1.0, 2.0}));
  EXPECT_EQ(f.plant.sensors.d.adc.bits, 12);
  EXPECT_DOUBLE_EQ(f.plant.sensors.d.adc.max, 0.15);  // default kept
  ASSERT_EQ(f.plant.faults.size(), 1U);
  EXPECT_EQ(f.plant.faults[0].kind, FaultKind::stuck_adc);
  EXPECT_EQ(f.plant.faults[0].channel, Channel::e);
  EXPECT_DOUBLE_EQ(f.excitation.temperature.end_degc, 60.0);
  EXPECT_DOUBLE_EQ(f.excitation.loops.duration_s, 12.0);
  EXPECT_DOUBLE_EQ(f.excitation.loops.hold_max_s, 0.5);
}

// Energy sanity: for every example configuration the cyclic integral of E dD over the closed
// second cycle of 0 .. 2e6 V/m is never negative (the stack generates no energy) and clearly
// positive where a dissipative effect (hysteresis, creep) is on; every example loads and runs.
TEST(PlantExamples, EveryConfigLoadsAndItsLoopDissipates) {
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator{test::config_dir()}) {
    if (entry.path().extension() != ".yaml") continue;
    ++count;
    SCOPED_TRACE(entry.path().filename().string());
    const PlantFile file = load_plant_file(entry.path());
    PlantConfig c = file.plant;
    c.faults.clear();
    const double fs = c.sample_rate_hz;
    const auto e = test::cosine_cycles(fs, 5.0, 3);
    const auto out = test::run_field(c, e, 0.0, 25.0);
    const std::size_t cycle = e.size() / 3;
    ASSERT_NEAR(e[2 * cycle], e[cycle], 1e-6);  // the integral runs over a closed cycle
    const double energy = test::loop_energy(out, cycle, 2 * cycle);
    const double rounding = 1e-9 * 2.0e6 * 0.1;  // relative to E_max D_max
    EXPECT_GT(energy, -rounding);
    if (c.hysteresis.enabled || c.creep.enabled) {
      EXPECT_GT(energy, 1.0);  // J/m^3 per cycle
    }
    for (const auto& o : out)
      ASSERT_TRUE(std::isfinite(o.d_meas_c_per_m2));
  }
  EXPECT_GE(count, 10);
}

}  // namespace
}  // namespace selfsense::plant
