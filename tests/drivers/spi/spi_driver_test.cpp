// The SPI driver against the chip emulators at its SpiBus / GpioLine seam, in simulated time:
// set-up with read-back verification, the samples' scaling through the front end, the DAC
// frames, every fault path (CRC errors, re-initialisation, stuck data, missing conversions,
// clipped and out-of-range inputs, the amplifier's fault line, a dead bus), the stack's
// temperature on a spare channel, data-ready pacing, and no allocation or lock on the real-time
// path.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "selfsense/runtime/driver.hpp"
#include "support/allocation_counter.hpp"
#include "support/spi/spi_bench.hpp"

namespace selfsense::test {
namespace {

using runtime::CycleTrigger;
using runtime::DriverStatus;
namespace adc = drivers::spi::ads131m04;

constexpr double kRate = 10000.0;
constexpr std::int64_t kPeriodNs = 100'000;

plant::PlantConfig quiet_plant() {
  plant::PlantConfig p;  // linear, with the sensor noise that keeps real codes from repeating
  p.sample_rate_hz = kRate;
  p.sensors.e.noise_std = 200.0;
  p.sensors.d.noise_std = 7e-6;
  return p;
}

struct Fixture {
  explicit Fixture(const drivers::spi::SpiConfig& c = emulated_spi_config(kRate),
                   const plant::PlantConfig& p = quiet_plant())
      : bench(std::make_unique<SpiBench>(c, p)) {}
  bool start(std::string* why = nullptr) const {
    std::string w;
    const bool ok = bench->driver.configure({1.0 / kRate}, &w) && bench->driver.activate(&w);
    if (why != nullptr) *why = w;
    return ok;
  }
  // One paced cycle: wait for data-ready, read, write.
  DriverStatus cycle(double command = 0.0) {
    EXPECT_EQ(bench->driver.cycle_trigger()->wait(3 * kPeriodNs), CycleTrigger::Result::kReady);
    const DriverStatus s = bench->driver.read(in);
    EXPECT_EQ(bench->driver.write({command}), DriverStatus::kOk);
    return s;
  }
  std::unique_ptr<SpiBench> bench;
  runtime::InputSample in{};
};

TEST(SpiDriver, ActivationConfiguresTheAdcAndVerifiesEveryRegister) {
  Fixture f;
  std::string why;
  ASSERT_TRUE(f.start(&why)) << why;
  const Ads131m04Emulator& a = f.bench->adc;
  // MODE: 24-bit words, SPI timeout, input CRC on, RESET acknowledged.
  EXPECT_EQ(a.reg(adc::kRegMode), adc::kModeWord24 | adc::kModeTimeout | adc::kModeRxCrcEn);
  EXPECT_EQ(a.reg(adc::kRegClock), 0x0F02);  // all channels, OSR 128, high resolution
  EXPECT_EQ(a.reg(adc::kRegGain), 0x0000);
  EXPECT_DOUBLE_EQ(a.data_rate_hz(), kRate);
  EXPECT_EQ(a.rejected_commands(), 0);
  // The DAC: reset, powered, LDAC ignored, internal reference, then the safe code; the
  // amplifier enabled only after.
  EXPECT_TRUE(f.bench->dac.reference_on());
  EXPECT_EQ(f.bench->dac.ldac_mask(), 3);
  EXPECT_EQ(f.bench->dac.code(0), 0);
  EXPECT_TRUE(f.bench->enable.level());
  f.bench->driver.deactivate();
  EXPECT_FALSE(f.bench->enable.level());
}

TEST(SpiDriver, ARegisterThatReadsBackWrongFailsActivation) {
  Fixture f;
  f.bench->adc.corrupt_readback(adc::kRegClock, 0x0004);
  std::string why;
  EXPECT_FALSE(f.start(&why));
  EXPECT_NE(why.find("driver.adc: adc: register 0x0003 reads back 0x0F06 after writing 0x0F02 "
                     "(read-back verification)"),
            std::string::npos)
      << why;
  EXPECT_FALSE(f.bench->enable.level());  // the amplifier stays off
  EXPECT_EQ(f.bench->driver.cycle_trigger(), nullptr);
}

TEST(SpiDriver, ANonRespondingBusFailsActivationWithTheReason) {
  Fixture f;
  f.bench->adc.set_dead(true);
  std::string why;
  EXPECT_FALSE(f.start(&why));
  EXPECT_NE(why.find("the SPI transfer failed (command 0x0011)"), std::string::npos) << why;
}

TEST(SpiDriver, SamplesAreScaledThroughTheFrontEnd) {
  Fixture f;
  ASSERT_TRUE(f.start());
  const double e_cmd = 1.2e6;
  for (int k = 0; k < 20; ++k)
    ASSERT_EQ(f.cycle(e_cmd), DriverStatus::kOk) << k;
  // The DAC code for 1.2e6 V/m: u = 72 V, 2.4 V at the DAC, of 5 V full scale.
  EXPECT_EQ(f.bench->dac.code(0), 31457);
  const plant::StepOutput& truth = f.bench->last;
  // One ADC LSB on E is 1.2 V / 2^23 * 125 / 60 um = 0.3 V/m; on D 1.2 V / 2^23 * 330 uF /
  // (167 * 25 mm^2) = 1.13e-8 C/m^2. The DAC's
  // LSB (5 V / 65536 * 30 / 60 um = 38 V/m) is the field's own quantisation.
  EXPECT_NEAR(f.in.e, truth.e_meas_v_per_m, 0.5);
  EXPECT_NEAR(f.in.d, truth.d_meas_c_per_m2, 1.2e-8);
  EXPECT_NEAR(f.in.e, e_cmd, 40.0 + 5 * 200.0);  // DAC LSB and 5 sigma of the sensor noise
  EXPECT_EQ(f.in.device_status & adc::kStatusDrdyMask, adc::kStatusDrdyMask);
  EXPECT_EQ(f.in.timestamp_ns, f.bench->clock.now_ns());
  EXPECT_EQ(f.bench->driver.counters().reads, 20U);
  EXPECT_EQ(f.bench->driver.counters().writes, 20U);
}

// A linear sensor (0.25 V + 5 mV/K at the ADC, the defaults) on channel 2: the stack's temperature
// from the same frame as E and D; a reading beyond the ADC's full scale or outside range_degc is no
// temperature (NaN, counted) and not a fault.
TEST(SpiDriver, TheStackTemperatureIsReadFromItsOwnChannel) {
  drivers::spi::SpiConfig c = emulated_spi_config(kRate);
  c.temp.wired = true;
  c.temp.range_degc = {-40.0, 60.0};
  Fixture f(c);
  ASSERT_TRUE(f.start());
  EXPECT_TRUE(f.bench->driver.has_temperature());
  f.bench->ambient_degc = 37.5;
  for (int k = 0; k < 5; ++k)
    ASSERT_EQ(f.cycle(), DriverStatus::kOk) << k;
  // One LSB is 1.2 V / 2^23 / 5 mV/K = 2.9e-5 K.
  EXPECT_NEAR(f.in.temp_ref, 37.5, 1e-4);
  EXPECT_EQ(f.bench->driver.spi_counters().temp_out_of_range, 0U);
  f.bench->ambient_degc = 65.0;  // 0.575 V: inside the full scale, outside range_degc
  EXPECT_EQ(f.cycle(), DriverStatus::kOk);
  EXPECT_TRUE(std::isnan(f.in.temp_ref));
  EXPECT_TRUE(std::isfinite(f.in.e));
  f.bench->ambient_degc = 250.0;  // 1.5 V: clipped at the ADC
  EXPECT_EQ(f.cycle(), DriverStatus::kOk);
  EXPECT_TRUE(std::isnan(f.in.temp_ref));
  EXPECT_EQ(f.bench->driver.spi_counters().temp_out_of_range, 2U);
  EXPECT_EQ(f.bench->driver.counters().bad_data, 0U);
  f.bench->ambient_degc = -12.25;
  EXPECT_EQ(f.cycle(), DriverStatus::kOk);
  EXPECT_NEAR(f.in.temp_ref, -12.25, 1e-4);

  // Its PGA gain reaches the gain register beside E's and D's (gain 4: code 2 in bits 8..10).
  drivers::spi::SpiConfig gained = c;
  gained.temp.pga_gain = 4;
  gained.temp.range_degc = {-40.0, 5.0};  // 0.275 V at 5 degC, of 0.3 V full scale
  Fixture g(gained);
  std::string why;
  ASSERT_TRUE(g.start(&why)) << why;
  EXPECT_EQ(g.bench->adc.reg(adc::kRegGain), 0x0200);
  g.bench->ambient_degc = 2.0;
  EXPECT_EQ(g.cycle(), DriverStatus::kOk);
  EXPECT_NEAR(g.in.temp_ref, 2.0, 1e-4);

  Fixture none;  // without the section: no temperature, whatever the spare channel reads
  ASSERT_TRUE(none.start());
  EXPECT_FALSE(none.bench->driver.has_temperature());
  EXPECT_EQ(none.cycle(), DriverStatus::kOk);
  EXPECT_TRUE(std::isnan(none.in.temp_ref));
}

TEST(SpiDriver, CrcErrorsAreCountedFaultsAndThreeInARowReinitialiseTheAdc) {
  Fixture f;
  ASSERT_TRUE(f.start());
  ASSERT_EQ(f.cycle(), DriverStatus::kOk);
  f.bench->adc.inject_crc_errors(1);
  EXPECT_EQ(f.cycle(), DriverStatus::kBadData);
  EXPECT_TRUE(std::isnan(f.in.e));  // a corrupted frame gives no number
  EXPECT_EQ(f.cycle(), DriverStatus::kOk);
  EXPECT_EQ(f.bench->driver.spi_counters().crc_errors, 1U);
  EXPECT_EQ(f.bench->driver.counters().bad_data, 1U);
  EXPECT_EQ(f.bench->driver.adc_state(), drivers::spi::AdcState::kRunning);

  f.bench->adc.inject_crc_errors(3);
  for (int i = 0; i < 3; ++i)
    EXPECT_EQ(f.cycle(), DriverStatus::kBadData);
  EXPECT_EQ(f.bench->driver.adc_state(), drivers::spi::AdcState::kReinitRequested);
  const long frames = f.bench->adc.frames();
  EXPECT_EQ(f.cycle(), DriverStatus::kDisconnected);
  EXPECT_EQ(f.bench->adc.frames(), frames);  // the loop leaves the bus alone meanwhile
  f.bench->driver.service(0);
  EXPECT_EQ(f.bench->driver.adc_state(), drivers::spi::AdcState::kRunning);
  EXPECT_EQ(f.bench->driver.counters().reconnects, 1U);
  EXPECT_EQ(f.cycle(), DriverStatus::kOk);
  EXPECT_EQ(f.bench->driver.spi_counters().crc_errors, 4U);
}

// Every cause SpiCounters keeps reaches counters() as an event under its field's name (the
// daemon's status and telemetry show nothing else), and CRC errors in the common field.
TEST(SpiDriver, CountersCarryEveryCauseAsANamedEvent) {
  Fixture f;
  ASSERT_TRUE(f.start());
  ASSERT_EQ(f.cycle(), DriverStatus::kOk);
  f.bench->adc.inject_crc_errors(2);
  EXPECT_EQ(f.cycle(), DriverStatus::kBadData);
  EXPECT_EQ(f.cycle(), DriverStatus::kBadData);
  EXPECT_EQ(f.cycle(), DriverStatus::kOk);
  const runtime::DriverCounters c = f.bench->driver.counters();
  EXPECT_EQ(c.crc_errors, 2U);
  const std::vector<std::string> names{
      "crc_errors",      "input_crc_errors", "clipped",          "out_of_range", "no_new_data",
      "stuck",           "drdy_missed",      "command_clipped",  "amp_faults",   "adc_resets",
      "reinit_failures", "reinits",          "temp_out_of_range"};
  ASSERT_EQ(c.event_list().size(), names.size());
  for (std::size_t i = 0; i < names.size(); ++i) {
    ASSERT_NE(c.events[i].name, nullptr);
    EXPECT_EQ(std::string(c.events[i].name), names[i]);
  }
  EXPECT_EQ(c.events[0].value, 2U);
  EXPECT_EQ(c.events[1].value, 0U);
  // The same names in the same order on every call (the status keeps them as published).
  EXPECT_EQ(std::string(f.bench->driver.counters().events[11].name), "reinits");
}

TEST(SpiDriver, FailedReinitialisationsRetryWithBackOffAndAreCounted) {
  Fixture f;
  ASSERT_TRUE(f.start());
  ASSERT_EQ(f.cycle(), DriverStatus::kOk);
  f.bench->adc.spontaneous_reset();  // a supply dip: registers lost, STATUS.RESET set
  EXPECT_EQ(f.cycle(), DriverStatus::kDeviceFault);
  EXPECT_EQ(f.bench->driver.spi_counters().adc_resets, 1U);
  f.bench->adc.set_dead(true);
  f.bench->driver.service(0);
  EXPECT_EQ(f.bench->driver.adc_state(), drivers::spi::AdcState::kReinitFailing);
  f.bench->driver.service(0);  // within the back-off: no attempt
  EXPECT_EQ(f.bench->driver.counters().retries, 1U);
  f.bench->clock.advance_ns(10'000'000);  // 10 ms: the first back-off
  f.bench->driver.service(0);
  EXPECT_EQ(f.bench->driver.counters().retries, 2U);
  f.bench->clock.advance_ns(10'000'000);  // the back-off doubled to 20 ms: not yet
  f.bench->driver.service(0);
  EXPECT_EQ(f.bench->driver.counters().retries, 2U);
  f.bench->adc.set_dead(false);
  f.bench->clock.advance_ns(10'000'000);
  f.bench->driver.service(0);
  EXPECT_EQ(f.bench->driver.adc_state(), drivers::spi::AdcState::kRunning);
  EXPECT_EQ(f.bench->driver.counters().reconnects, 1U);
  EXPECT_EQ(f.bench->adc.reg(adc::kRegClock), 0x0F02);  // configured again
  EXPECT_EQ(f.cycle(), DriverStatus::kOk);
}

TEST(SpiDriver, AStuckConverterIsStaleAfterStuckFrames) {
  drivers::spi::SpiConfig c = emulated_spi_config(kRate);
  c.faults.stuck_frames = 5;
  Fixture f(c);
  ASSERT_TRUE(f.start());
  for (int k = 0; k < 50; ++k)
    ASSERT_EQ(f.cycle(1e6), DriverStatus::kOk) << k;
  f.bench->adc.set_stuck(true);
  // Frozen at the conversion read last: the 5th frame repeating it is stale.
  for (int k = 0; k < 4; ++k)
    EXPECT_EQ(f.cycle(1e6), DriverStatus::kOk) << k;
  EXPECT_EQ(f.cycle(1e6), DriverStatus::kStale);
  EXPECT_EQ(f.bench->driver.spi_counters().stuck, 1U);
  f.bench->adc.set_stuck(false);
  EXPECT_EQ(f.cycle(1e6), DriverStatus::kOk);
}

// Found by fuzz_spi_frame (corpus/spi_frame/regression-stuck-*): the first frame after
// activation was compared with codes never read (0, 0), the first after a re-initialisation
// with the codes before it, so a converter at 0 was stuck one frame early (with stuck_frames 1:
// the first read of the loop stale).
TEST(SpiDriver, TheStuckCountStartsAtTheFirstFrameOfEachInitialisation) {
  drivers::spi::SpiConfig c = emulated_spi_config(kRate);
  c.faults.stuck_frames = 2;
  Fixture f(c);
  f.bench->adc.set_stuck(true);  // frozen at 0 from power-up: every code 0, inside the ranges
  ASSERT_TRUE(f.start());
  EXPECT_EQ(f.cycle(), DriverStatus::kOk);  // the first frame: nothing to repeat
  EXPECT_EQ(f.cycle(), DriverStatus::kOk);  // one repeat
  EXPECT_EQ(f.cycle(), DriverStatus::kStale);
  EXPECT_EQ(f.bench->driver.spi_counters().stuck, 1U);
  f.bench->adc.spontaneous_reset();
  EXPECT_EQ(f.cycle(), DriverStatus::kDeviceFault);
  f.bench->driver.service(0);
  ASSERT_EQ(f.bench->driver.adc_state(), drivers::spi::AdcState::kRunning);
  EXPECT_EQ(f.cycle(), DriverStatus::kOk);  // the first frame of the re-initialised ADC
  EXPECT_EQ(f.cycle(), DriverStatus::kOk);
  EXPECT_EQ(f.cycle(), DriverStatus::kStale);
  EXPECT_EQ(f.bench->driver.spi_counters().stuck, 2U);
}

TEST(SpiDriver, FramesWithoutANewConversionAreStaleBeyondTheAllowance) {
  Fixture f;  // stale_frames 2
  ASSERT_TRUE(f.start());
  ASSERT_EQ(f.cycle(), DriverStatus::kOk);
  // Reads without waiting for data-ready: the same conversion again (STATUS.DRDY clear).
  EXPECT_EQ(f.bench->driver.read(f.in), DriverStatus::kOk);
  EXPECT_EQ(f.bench->driver.read(f.in), DriverStatus::kOk);
  EXPECT_EQ(f.bench->driver.read(f.in), DriverStatus::kStale);
  EXPECT_EQ(f.bench->driver.spi_counters().no_new_data, 3U);
  EXPECT_EQ(f.cycle(), DriverStatus::kOk);
}

TEST(SpiDriver, ClippedAndOutOfRangeInputsAreBadData) {
  drivers::spi::SpiConfig c = emulated_spi_config(kRate);
  c.e.range_v_per_m = {-0.5e6, 1.0e6};
  Fixture f(c);
  ASSERT_TRUE(f.start());
  for (int k = 0; k < 5; ++k)
    ASSERT_EQ(f.cycle(0.8e6), DriverStatus::kOk);
  EXPECT_EQ(f.cycle(1.2e6), DriverStatus::kOk);  // the command reaches the next conversion
  EXPECT_EQ(f.cycle(1.2e6), DriverStatus::kBadData);
  EXPECT_EQ(f.cycle(1.2e6), DriverStatus::kBadData);
  EXPECT_EQ(f.bench->driver.spi_counters().out_of_range, 2U);
  // Beyond the divider's 150 V: the ADC clips.
  c.e.range_v_per_m = {-0.5e6, 2.4e6};
  c.amplifier.gain_v_per_v = 50.0;  // 250 V possible from the DAC
  Fixture g(c);
  ASSERT_TRUE(g.start());
  for (int k = 0; k < 3; ++k)
    g.cycle(3.0e6);
  EXPECT_EQ(g.cycle(3.0e6), DriverStatus::kBadData);
  EXPECT_GE(g.bench->driver.spi_counters().clipped, 1U);
}

TEST(SpiDriver, TheAmplifierFaultLineIsADeviceFault) {
  Fixture f;
  ASSERT_TRUE(f.start());
  ASSERT_EQ(f.cycle(), DriverStatus::kOk);
  f.bench->fault.set_level(false, f.bench->clock.now_ns());  // active low: fault
  f.bench->driver.service(0);
  EXPECT_TRUE(f.bench->driver.amplifier_fault());
  EXPECT_EQ(f.cycle(), DriverStatus::kDeviceFault);
  EXPECT_EQ(f.bench->driver.counters().device_faults, 1U);
  f.bench->fault.set_level(true, f.bench->clock.now_ns());
  f.bench->driver.service(0);
  EXPECT_EQ(f.cycle(), DriverStatus::kOk);
  EXPECT_EQ(f.bench->driver.spi_counters().amp_faults, 1U);
}

TEST(SpiDriver, AFaultPresentAtActivationIsSeenAtOnce) {
  Fixture f;
  f.bench->fault.set_level(false, 0);
  ASSERT_TRUE(f.start());
  EXPECT_EQ(f.cycle(), DriverStatus::kDeviceFault);
}

TEST(SpiDriver, DataReadyPacesTheCycleAtTheAdcRate) {
  Fixture f;
  ASSERT_TRUE(f.start());
  CycleTrigger* t = f.bench->driver.cycle_trigger();
  ASSERT_NE(t, nullptr);
  ASSERT_EQ(t->wait(kPeriodNs * 3), CycleTrigger::Result::kReady);
  const std::int64_t t0 = f.bench->clock.now_ns();
  for (int k = 1; k <= 100; ++k) {
    ASSERT_EQ(t->wait(kPeriodNs * 3), CycleTrigger::Result::kReady);
    EXPECT_EQ(f.bench->clock.now_ns() - t0, k * kPeriodNs);
    EXPECT_EQ(f.bench->driver.read(f.in), DriverStatus::kOk);
  }
  // A loop late by 3.5 periods: the queued edges are skipped to the newest and counted.
  f.bench->clock.advance_ns(kPeriodNs * 7 / 2);
  ASSERT_EQ(t->wait(kPeriodNs * 3), CycleTrigger::Result::kReady);
  EXPECT_EQ(f.bench->driver.spi_counters().drdy_missed, 2U);
  EXPECT_EQ(f.bench->driver.read(f.in), DriverStatus::kOk);
  // No conversions (STANDBY-like: a dead bus stops the edges): the wait times out.
  f.bench->adc.set_dead(true);
  EXPECT_EQ(t->wait(kPeriodNs * 3), CycleTrigger::Result::kError);
  f.bench->adc.set_dead(false);
  // Timer pacing offers no trigger.
  drivers::spi::SpiConfig c = emulated_spi_config(kRate);
  c.pace = drivers::spi::Pace::kTimer;
  Fixture timer(c);
  ASSERT_TRUE(timer.start());
  EXPECT_EQ(timer.bench->driver.cycle_trigger(), nullptr);
}

TEST(SpiDriver, ADeadDacIsADisconnectAndTheSafeOutputFollowsAtDeactivation) {
  Fixture f;
  ASSERT_TRUE(f.start());
  ASSERT_EQ(f.cycle(1e6), DriverStatus::kOk);
  EXPECT_GT(f.bench->dac.code(0), 0);
  f.bench->dac.set_dead(true);
  EXPECT_EQ(f.bench->driver.write({1e6}), DriverStatus::kDisconnected);
  EXPECT_EQ(f.bench->driver.counters().errors, 1U);
  f.bench->dac.set_dead(false);
  EXPECT_EQ(f.bench->driver.write({std::nan("")}), DriverStatus::kOk);  // NaN: E = 0
  EXPECT_EQ(f.bench->dac.code(0), 0);
  ASSERT_EQ(f.bench->driver.write({1e6}), DriverStatus::kOk);
  EXPECT_EQ(f.bench->driver.write({1e9}), DriverStatus::kOk);
  EXPECT_EQ(f.bench->dac.code(0), 65535);
  EXPECT_EQ(f.bench->driver.spi_counters().command_clipped, 1U);
  f.bench->driver.deactivate();
  EXPECT_EQ(f.bench->dac.code(0), 0);
}

TEST(SpiDriver, TheRealTimePathNeitherAllocatesNorLocks) {
  Fixture f;
  ASSERT_TRUE(f.start());
  ASSERT_EQ(f.cycle(), DriverStatus::kOk);
  std::size_t allocations = 0;
  std::size_t locks = 0;
  int ok = 0;
  {
    const AllocationCounter counter;
    CycleTrigger* t = f.bench->driver.cycle_trigger();
    for (int k = 0; k < 1000; ++k) {
      if (t->wait(kPeriodNs * 3) != CycleTrigger::Result::kReady) continue;
      if (f.bench->driver.read(f.in) == DriverStatus::kOk) ++ok;
      static_cast<void>(f.bench->driver.write({1e6}));
    }
    allocations = counter.count();
    locks = counter.locks();
  }
  EXPECT_EQ(ok, 1000);
  EXPECT_EQ(allocations, 0U);
  EXPECT_EQ(locks, 0U);
}

}  // namespace
}  // namespace selfsense::test
