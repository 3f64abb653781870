// Fault injection: explicit calls and schedule entries, each visible in values and status.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "plant_test_util.hpp"
#include "selfsense/plant/plant.hpp"
#include "selfsense/plant_io/plant_yaml.hpp"

namespace selfsense::plant {
namespace {

PlantConfig base() {
  PlantConfig c{};
  c.sample_rate_hz = 10000.0;
  c.sensors.d.adc = AdcConfig{true, 16, -0.05, 0.15};
  c.sensors.e.adc = AdcConfig{true, 16, -1.0e6, 3.0e6};
  return c;
}

// A slow ramp so that every sample differs from the previous one.
std::vector<StepOutput> run_with(Plant& plant, std::size_t n) {
  std::vector<StepOutput> out;
  for (std::size_t k = 0; k < n; ++k) {
    out.push_back(plant.step(StepInput{1.0e3 * static_cast<double>(k), 0.0, 25.0}));
  }
  return out;
}

TEST(PlantFaults, NanSampleOnOneChannel) {
  Plant plant{base()};
  ASSERT_TRUE(plant.inject(FaultKind::nan_sample, Channel::d, 5, 1));
  const auto out = run_with(plant, 10);
  EXPECT_TRUE(std::isnan(out[5].d_meas_c_per_m2));
  EXPECT_FALSE(std::isnan(out[5].e_meas_v_per_m));
  EXPECT_NE(out[5].status & kNanSample, 0U);
  EXPECT_FALSE(std::isnan(out[6].d_meas_c_per_m2));
  EXPECT_EQ(out[6].status & kFaultMask, 0U);
}

TEST(PlantFaults, StuckAdcHoldsTheLastValue) {
  Plant plant{base()};
  plant.inject(FaultKind::stuck_adc, Channel::e, 4, 3);
  const auto out = run_with(plant, 10);
  for (std::size_t k = 4; k < 7; ++k) {
    EXPECT_DOUBLE_EQ(out[k].e_meas_v_per_m, out[3].e_meas_v_per_m);
    EXPECT_NE(out[k].status & kStuckAdc, 0U);
  }
  EXPECT_GT(out[7].e_meas_v_per_m, out[3].e_meas_v_per_m);
  EXPECT_GT(out[6].e_v_per_m, out[3].e_v_per_m);  // the truth moves on
}

TEST(PlantFaults, OutOfRangeSampleLiesBeyondTheConverterRange) {
  Plant plant{base()};
  plant.inject(FaultKind::out_of_range, Channel::both, 2, 1);
  const auto out = run_with(plant, 4);
  EXPECT_GT(out[2].d_meas_c_per_m2, 0.15);
  EXPECT_GT(out[2].e_meas_v_per_m, 3.0e6);
  EXPECT_NE(out[2].status & kOutOfRange, 0U);
}

TEST(PlantFaults, MissedDataReadyRepeatsTheLastSample) {
  Plant plant{base()};
  plant.inject(FaultKind::missed_data_ready, Channel::both, 3, 2);
  const auto out = run_with(plant, 6);
  EXPECT_DOUBLE_EQ(out[4].e_meas_v_per_m, out[2].e_meas_v_per_m);
  EXPECT_DOUBLE_EQ(out[4].d_meas_c_per_m2, out[2].d_meas_c_per_m2);
  EXPECT_NE(out[3].status & kMissedDataReady, 0U);
  EXPECT_EQ(out[5].status & kMissedDataReady, 0U);
}

TEST(PlantFaults, LateSampleCarriesItsLatency) {
  Plant plant{base()};
  plant.inject(FaultKind::late_sample, Channel::both, 1, 1, 3e-5);
  const auto out = run_with(plant, 3);
  EXPECT_DOUBLE_EQ(out[1].latency_s, 3e-5);
  EXPECT_NE(out[1].status & kLateSample, 0U);
  EXPECT_DOUBLE_EQ(out[2].latency_s, 0.0);
}

TEST(PlantFaults, AmplifierFaultDischargesTheStack) {
  PlantConfig c = base();
  c.amplifier.enabled = true;
  Plant plant{c};
  for (int k = 0; k < 100; ++k)
    plant.step(StepInput{1.0e6, 0.0, 25.0});
  plant.inject(FaultKind::amplifier_fault, Channel::both, 100, 1000);
  StepOutput o{};
  for (int k = 0; k < 100; ++k)
    o = plant.step(StepInput{1.0e6, 0.0, 25.0});
  EXPECT_NE(o.status & kAmplifierFault, 0U);
  EXPECT_NEAR(o.u_v, 0.0, 1e-9);
}

TEST(PlantFaults, SensorDisconnectReadsNothing) {
  Plant plant{base()};
  plant.inject(FaultKind::sensor_disconnect, Channel::d, 5, 5);
  const auto out = run_with(plant, 12);
  EXPECT_NEAR(out[7].d_meas_c_per_m2, 0.0, 1e-5);
  EXPECT_GT(out[7].d_c_per_m2, 1e-4);
  EXPECT_NE(out[7].status & kSensorDisconnect, 0U);
}

TEST(PlantFaults, FaultsDoNotDisturbTheTruthOrTheRandomSequence) {
  PlantConfig c = base();
  c.sensors.d.noise_std = 1e-5;
  Plant clean{c};
  Plant faulty{c};
  faulty.inject(FaultKind::nan_sample, Channel::both, 3, 5);
  const auto a = run_with(clean, 20);
  const auto b = run_with(faulty, 20);
  for (std::size_t k = 0; k < a.size(); ++k)
    EXPECT_DOUBLE_EQ(a[k].s, b[k].s);
  EXPECT_DOUBLE_EQ(a[15].d_meas_c_per_m2, b[15].d_meas_c_per_m2);
}

TEST(PlantFaults, ScheduleFromTheConfigurationFires) {
  const PlantFile file = load_plant_file(test::config_dir() / "faults.yaml");
  Plant plant{file.plant};
  std::uint32_t seen = 0;
  for (int k = 0; k < 10000; ++k)
    seen |= plant.step(StepInput{1.0e6, 0.0, 25.0}).status;
  for (const std::uint32_t bit : {kNanSample, kStuckAdc, kOutOfRange, kMissedDataReady, kLateSample,
                                  kSensorDisconnect, kAmplifierFault}) {
    EXPECT_NE(seen & bit, 0U) << "bit " << bit;
  }
}

TEST(PlantFaults, TableIsBoundedAndCanBeCleared) {
  Plant plant{base()};
  for (std::size_t i = 0; i < kMaxScheduledFaults; ++i) {
    EXPECT_TRUE(plant.inject(FaultKind::nan_sample, Channel::d, 1000, 1));
  }
  EXPECT_FALSE(plant.inject(FaultKind::nan_sample, Channel::d, 1000, 1));
  plant.clear_faults();
  EXPECT_TRUE(plant.inject(FaultKind::nan_sample, Channel::d, 1000, 1));
}

}  // namespace
}  // namespace selfsense::plant
