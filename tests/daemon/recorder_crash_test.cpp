// kill -9 of a recording process at random moments (fixed seed): every file it left is a valid
// contract recording ending at a row boundary, and every row up to its last flush is there.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <fstream>
#include <random>
#include <thread>

#include "daemon/recording_support.hpp"
#include "selfsense/daemon/recorder.hpp"

namespace selfsense::daemon {
namespace {

using testing::ScratchDir;
using testing::synthetic_sample;

// Shared with the child: what it has seen flushed, and that it is recording.
struct Progress {
  std::atomic<std::uint64_t> rows_flushed{0};
  std::atomic<bool> recording{false};
};

[[noreturn]] void record_until_killed(const std::filesystem::path& dir, Progress& progress) {
  try {
    RecorderConfig config;
    config.directory = dir;
    config.prefix = "crash";
    config.sample_time_s = testing::kTs;
    config.rotate_bytes = std::size_t{256} * 1024;  // rotations happen within the run
    config.flush_period_ms = 5.0;
    config.ring_capacity = 1U << 14U;
    config.flight.dump_on_fault = false;
    Recorder recorder(config);
    recorder.start();
    recorder.start_file();
    progress.recording.store(true);
    for (std::int64_t k = 0;; ++k) {
      while (recorder.queued() + 1 >= recorder.capacity())
        std::this_thread::yield();
      recorder.push(synthetic_sample(k));
      if (k % 256 == 0) progress.rows_flushed.store(recorder.counters().rows_flushed);
    }
  } catch (...) {
    _exit(2);
  }
}

std::string last_byte(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  in.seekg(-1, std::ios::end);
  return std::string(1, static_cast<char>(in.get()));
}

TEST(RecorderCrash, KillNineLeavesParseableFilesWithEveryFlushedRow) {
  std::mt19937 rng(20261123);
  std::uniform_int_distribution<int> delay_ms(20, 400);
  for (int round = 0; round < 8; ++round) {
    const ScratchDir dir("crash" + std::to_string(round));
    void* const memory =
        mmap(nullptr, sizeof(Progress), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
    ASSERT_NE(memory, MAP_FAILED);
    auto* progress = new (memory) Progress;
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) record_until_killed(dir.path(), *progress);

    for (int i = 0; i < 5000 && !progress->recording.load(); ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    ASSERT_TRUE(progress->recording.load());
    std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms(rng)));
    ASSERT_EQ(kill(child, SIGKILL), 0);
    int status = 0;
    ASSERT_EQ(waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFSIGNALED(status)) << "the child ended by itself: " << status;
    const std::uint64_t flushed = progress->rows_flushed.load();
    munmap(memory, sizeof(Progress));

    // Only whole recordings remain: no temporary, no empty or header-only file.
    for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
      EXPECT_EQ(entry.path().extension(), ".csv") << entry.path();
    const testing::ReadBack back = testing::read_back(dir.path(), "crash-");
    for (const auto& file : back.files)
      EXPECT_EQ(last_byte(file), "\n") << file;
    ASSERT_GE(back.cycle.size(), flushed) << "round " << round;
    for (std::size_t i = 0; i < back.cycle.size(); ++i)
      ASSERT_EQ(back.cycle[i], static_cast<double>(i)) << "round " << round << " row " << i;
    std::cout << "round " << round << ": " << back.files.size() << " files, " << back.cycle.size()
              << " rows, " << flushed << " flushed\n";
  }
}

}  // namespace
}  // namespace selfsense::daemon
