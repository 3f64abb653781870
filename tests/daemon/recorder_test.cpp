#include "selfsense/daemon/recorder.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <thread>

#include "daemon/recording_support.hpp"

namespace selfsense::daemon {
namespace {

using testing::read_back;
using testing::ScratchDir;
using testing::synthetic_sample;

RecorderConfig config_in(const std::filesystem::path& dir) {
  RecorderConfig config;
  config.directory = dir;
  config.prefix = "rec";
  config.sample_time_s = testing::kTs;
  config.flush_period_ms = 100.0;
  config.flight.dump_on_fault = false;
  config.flight.seconds = 1.0;
  config.flight.post_trigger_seconds = 0.5;
  return config;
}

// Pushes cycles [from, to) without ever finding the ring full: waits for room like a producer
// that is paced to what the disk takes.
void push_paced(Recorder& recorder, std::int64_t from, std::int64_t to) {
  for (std::int64_t k = from; k < to; ++k) {
    while (recorder.queued() + 1 >= recorder.capacity())
      std::this_thread::sleep_for(std::chrono::microseconds(100));
    ASSERT_TRUE(recorder.push(synthetic_sample(k)));
  }
}

void expect_continuous(const testing::ReadBack& back, std::int64_t rows) {
  ASSERT_EQ(back.cycle.size(), static_cast<std::size_t>(rows));
  for (std::size_t i = 0; i < back.cycle.size(); ++i) {
    ASSERT_EQ(back.cycle[i], static_cast<double>(i)) << "row " << i;
    ASSERT_EQ(back.t[i], synthetic_sample(static_cast<std::int64_t>(i)).t) << "row " << i;
  }
}

TEST(RecorderConfig, EveryProblemNamesItsKey) {
  RecorderConfig config;
  config.rotate_bytes = 100;
  config.prefix = "../x";
  config.flush_period_ms = 0.0;
  config.flight.post_trigger_seconds = 20.0;
  const std::vector<std::string> problems = validate(config);
  ASSERT_EQ(problems.size(), 4U);
  EXPECT_EQ(problems[0].rfind("recorder.prefix: ", 0), 0U);
  EXPECT_EQ(problems[1], "recorder.rotate_bytes: 100 must be >= 4096");
  EXPECT_EQ(problems[2], "recorder.flush_period_ms: 0 must be within [1, 60000]");
  EXPECT_EQ(problems[3].rfind("recorder.flight.post_trigger_seconds: ", 0), 0U);
  EXPECT_THROW(Recorder{config}, RecorderError);
  EXPECT_TRUE(validate(RecorderConfig{}).empty());
}

// 60 s of a 20 kHz loop (1.2e6 samples), pushed as fast as the writer takes them: no drop, every
// row on disk in order, read back by the contract reader.
TEST(Recorder, SixtySecondsAt20kHzArriveWithoutADropInOrder) {
  const ScratchDir dir("rec-60s");
  RecorderConfig config = config_in(dir.path());
  config.ring_capacity = std::size_t{1} << 16U;
  config.rotate_bytes = std::size_t{64} << 20U;
  Recorder recorder(config);
  recorder.start();
  const std::filesystem::path first = recorder.start_file();
  EXPECT_EQ(recorder.current_path(), first);
  constexpr std::int64_t kRows = 1'200'000;
  push_paced(recorder, 0, kRows);
  const std::optional<std::filesystem::path> last = recorder.stop_file();
  recorder.stop();

  const RecorderCounters c = recorder.counters();
  EXPECT_EQ(c.samples_dropped, 0U);
  EXPECT_EQ(c.samples_pushed, static_cast<std::uint64_t>(kRows));
  EXPECT_EQ(c.rows_written, static_cast<std::uint64_t>(kRows));
  EXPECT_EQ(c.rows_flushed, c.rows_written);
  EXPECT_EQ(c.rows_lost + c.write_errors + c.time_breaks + c.rows_bad_time, 0U);
  const testing::ReadBack back = read_back(dir.path(), "rec-");
  EXPECT_EQ(back.files.front(), first);
  EXPECT_EQ(back.files.back(), last);
  EXPECT_EQ(c.files, back.files.size());
  EXPECT_GE(back.files.size(), 2U);  // ~150 MB at 64 MiB per file
  expect_continuous(back, kRows);
}

TEST(Recorder, AFullRingRefusesAndCountsEveryDrop) {
  const ScratchDir dir("rec-full");
  RecorderConfig config = config_in(dir.path());
  config.ring_capacity = 1000;  // 1024
  Recorder recorder(config);
  int accepted = 0;
  for (int k = 0; k < 3000; ++k)
    accepted += recorder.push(synthetic_sample(k)) ? 1 : 0;
  EXPECT_EQ(accepted, 1024);
  RecorderCounters c = recorder.counters();
  EXPECT_EQ(c.samples_pushed, 1024U);
  EXPECT_EQ(c.samples_dropped, 3000U - 1024U);
  recorder.start();
  recorder.stop();
  c = recorder.counters();
  EXPECT_EQ(c.samples_consumed, 1024U);
  EXPECT_EQ(c.samples_unrecorded, 1024U);  // consumed (and kept for the flight recorder)
  EXPECT_EQ(c.ring_high_water, 1024U);
}

TEST(Recorder, RotationSplitsIntoParseableFilesWithContinuousRows) {
  const ScratchDir dir("rec-rotate");
  RecorderConfig config = config_in(dir.path());
  config.rotate_bytes = 65536;
  Recorder recorder(config);
  recorder.start();
  recorder.start_file();
  constexpr std::int64_t kRows = 30000;
  push_paced(recorder, 0, kRows);
  recorder.stop();
  const testing::ReadBack back = read_back(dir.path(), "rec-");
  EXPECT_GE(back.files.size(), 60U);
  EXPECT_EQ(recorder.counters().files, back.files.size());
  for (const std::uintmax_t size : back.sizes)
    EXPECT_LE(size, config.rotate_bytes);
  expect_continuous(back, kRows);
  const io::Recording second = io::read_recording_csv(back.files[1]);
  EXPECT_EQ(second.comments[2], "file: 2 (rows continue from the previous file)");
  EXPECT_EQ(back.files[1].filename().string().substr(back.files[1].filename().string().size() - 9),
            "-0002.csv");
}

TEST(Recorder, BadTimesAreCountedAndNonFiniteValuesFlagged) {
  const ScratchDir dir("rec-time");
  Recorder recorder(config_in(dir.path()));
  recorder.start();
  recorder.start_file();
  runtime::LoopSample s = synthetic_sample(0);
  s.t_hat = runtime::LoopSample::kNone;
  recorder.push(s);
  recorder.push(synthetic_sample(1));
  runtime::LoopSample bad = synthetic_sample(2);
  bad.t = std::nan("");
  recorder.push(bad);                  // not written: counted
  recorder.push(synthetic_sample(1));  // t repeats: a new file
  recorder.push(synthetic_sample(2));
  recorder.stop();
  const RecorderCounters c = recorder.counters();
  EXPECT_EQ(c.rows_written, 4U);
  EXPECT_EQ(c.rows_bad_time, 1U);
  EXPECT_EQ(c.time_breaks, 1U);
  EXPECT_EQ(c.files, 2U);
  const auto files = testing::csv_files(dir.path(), "rec-");
  ASSERT_EQ(files.size(), 2U);
  const io::Recording first = io::read_recording_csv(files[0]);
  EXPECT_EQ(first.column("T_hat")[0], 0.0);
  EXPECT_EQ(first.column("nonfinite")[0], 4.0);
  EXPECT_EQ(first.column("nonfinite")[1], 0.0);
  EXPECT_EQ(io::read_recording_csv(files[1]).rows(), 2U);
}

TEST(Recorder, ControlRequestsAnswerAndNeverDropWhileNotRecording) {
  const ScratchDir dir("rec-control");
  Recorder recorder(config_in(dir.path()));
  EXPECT_THROW(recorder.start_file(), RecorderError);  // writer not running
  recorder.start();
  EXPECT_EQ(recorder.stop_file(), std::nullopt);
  EXPECT_EQ(recorder.current_path(), std::nullopt);
  push_paced(recorder, 0, 500);  // not recording: consumed, not dropped
  const std::filesystem::path path = recorder.start_file();
  EXPECT_THROW(recorder.start_file(), RecorderError);
  push_paced(recorder, 500, 1000);
  EXPECT_EQ(recorder.stop_file(), path);
  recorder.stop();
  const RecorderCounters c = recorder.counters();
  EXPECT_EQ(c.samples_dropped, 0U);
  EXPECT_EQ(c.samples_unrecorded + c.rows_written, 1000U);
  EXPECT_EQ(io::read_recording_csv(path).column("cycle").back(), 999.0);

  RecorderConfig missing = config_in(dir.path() / "nope");
  Recorder other(missing);
  other.start();
  try {
    other.start_file();
    FAIL() << "no error for a missing directory";
  } catch (const RecorderError& e) {
    EXPECT_NE(std::string(e.what()).find("recorder.directory"), std::string::npos);
  }
}

// A file-size limit makes write(2) fail (EFBIG) like a full disk: counted and reported, the file
// stays parseable, and the writer records again once the limit is gone.
TEST(Recorder, WriteErrorsAreCountedAndTheWriterCarriesOn) {
  const ScratchDir dir("rec-error");
  RecorderConfig config = config_in(dir.path());
  Recorder recorder(config);
  recorder.start();
  (void)std::signal(SIGXFSZ, SIG_IGN);
  rlimit saved{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &saved), 0);
  rlimit small = saved;
  small.rlim_cur = rlim_t{128} * 1024;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
  const std::filesystem::path path = recorder.start_file();
  push_paced(recorder, 0, 10000);  // ~1.5 MB
  // Wait until the writer has met the limit.
  for (int i = 0; i < 500 && recorder.counters().write_errors == 0; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  const RecorderCounters during = recorder.counters();
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &saved), 0);
  EXPECT_GT(during.write_errors, 0U);
  EXPECT_NE(recorder.last_error().find("File too large"), std::string::npos)
      << recorder.last_error();
  push_paced(recorder, 10000, 12000);
  recorder.stop();
  (void)std::signal(SIGXFSZ, SIG_DFL);
  const RecorderCounters c = recorder.counters();
  EXPECT_GT(c.rows_lost, 0U);
  EXPECT_EQ(c.rows_written + c.rows_lost, 12000U);
  const io::Recording r = io::read_recording_csv(path);
  EXPECT_EQ(r.rows(), c.rows_written);
  EXPECT_EQ(r.column("cycle").back(), 11999.0);  // recording resumed after the error
}

}  // namespace
}  // namespace selfsense::daemon
