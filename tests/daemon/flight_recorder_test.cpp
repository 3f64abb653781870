#include "selfsense/daemon/flight_recorder.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "daemon/recording_support.hpp"
#include "selfsense/daemon/recorder.hpp"

namespace selfsense::daemon {
namespace {

using testing::ScratchDir;
using testing::synthetic_sample;

FlightRecorderConfig flight_config() {
  FlightRecorderConfig config;
  config.seconds = 0.01;                // 200 samples at 20 kHz
  config.post_trigger_seconds = 0.001;  // 20 samples
  config.dump_on_fault = true;
  return config;
}

std::string name_of(unsigned bit) {
  return bit == 2 ? "stale sample" : "";
}

TEST(FlightRecorder, DumpHoldsTheLastSecondsInOrderAndNeverOverwrites) {
  const ScratchDir dir("flight-dump");
  FlightRecorder flight(flight_config(), dir.path(), testing::kTs, true);
  EXPECT_EQ(flight.capacity(), 200U);
  for (int k = 0; k < 500; ++k)
    flight.add(synthetic_sample(k));
  const auto path = dir.path() / "manual.csv";
  const FlightRecorder::Dump dump = flight.dump("operator asked\nfor it", path);
  ASSERT_TRUE(dump.error.empty()) << dump.error;
  EXPECT_EQ(dump.rows, 200U);
  const io::Recording r = io::read_recording_csv(path);
  ASSERT_EQ(r.rows(), 200U);
  for (std::size_t i = 0; i < r.rows(); ++i)
    ASSERT_EQ(r.column("cycle")[i], 300.0 + static_cast<double>(i));
  EXPECT_EQ(r.column("S")[5], synthetic_sample(305).s_ref);
  EXPECT_EQ(r.comments[1], "reason: operator asked for it");
  EXPECT_EQ(flight.dumps(), 1U);

  const FlightRecorder::Dump again = flight.dump("again", path);
  EXPECT_NE(again.error.find("exists"), std::string::npos);
  EXPECT_EQ(flight.dump_errors(), 1U);
}

TEST(FlightRecorder, NewFaultBitTriggersADumpAfterThePostTriggerTime) {
  const ScratchDir dir("flight-auto");
  FlightRecorder flight(flight_config(), dir.path(), testing::kTs, false, name_of);
  runtime::LoopSample s;
  for (int k = 0; k < 100; ++k)
    flight.add(synthetic_sample(k));
  EXPECT_FALSE(flight.auto_dump_pending());
  for (int k = 100; k < 120; ++k) {
    s = synthetic_sample(k);
    s.faults = k >= 105 ? 0x6U : 0x4U;  // bit 2 at cycle 100, bit 1 joins at 105
    flight.add(s);
    EXPECT_TRUE(flight.auto_dump_pending());
    EXPECT_FALSE(flight.auto_dump_due()) << k;
  }
  s = synthetic_sample(120);
  s.faults = 0x6U;
  flight.add(s);
  ASSERT_TRUE(flight.auto_dump_due());
  const FlightRecorder::Dump dump = flight.dump_auto();
  ASSERT_TRUE(dump.error.empty()) << dump.error;
  EXPECT_FALSE(flight.auto_dump_pending());
  const std::string name = dump.path.filename().string();
  EXPECT_EQ(name.rfind("flight-", 0), 0U);
  EXPECT_NE(name.find("-cycle100-fault1+stale_sample.csv"), std::string::npos) << name;
  const io::Recording r = io::read_recording_csv(dump.path);
  EXPECT_EQ(r.rows(), 121U);
  EXPECT_EQ(r.column("cycle").back(), 120.0);
  EXPECT_EQ(r.column("faults").back(), 6.0);
  EXPECT_FALSE(r.has("S"));
}

TEST(FlightRecorder, RecorderDumpsOnAFaultEvenWhenStoppedBeforeThePostTriggerTime) {
  const ScratchDir dir("flight-recorder");
  RecorderConfig config;
  config.directory = dir.path();
  config.sample_time_s = testing::kTs;
  config.flight = flight_config();
  config.flight.post_trigger_seconds = 0.005;
  Recorder recorder(config, name_of);
  recorder.start();
  for (int k = 0; k < 50; ++k) {
    runtime::LoopSample s = synthetic_sample(k);
    s.faults = k >= 40 ? 0x4U : 0U;
    ASSERT_TRUE(recorder.push(s));
  }
  while (recorder.counters().samples_consumed < 50)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  const FlightRecorder::Dump manual = recorder.dump_flight("check", dir.path() / "m.csv");
  EXPECT_TRUE(std::filesystem::exists(manual.path));
  EXPECT_THROW(recorder.dump_flight("check", dir.path() / "m.csv"), RecorderError);
  recorder.stop();  // the automatic dump is still pending: stop() writes it
  const RecorderCounters c = recorder.counters();
  EXPECT_EQ(c.flight_dumps, 2U);
  EXPECT_EQ(c.flight_dump_errors, 1U);
  const auto automatic = testing::csv_files(dir.path(), "flight-");
  ASSERT_EQ(automatic.size(), 1U);
  EXPECT_EQ(io::read_recording_csv(automatic[0]).rows(), 50U);
}

}  // namespace
}  // namespace selfsense::daemon
