#include "selfsense/daemon/recording_file.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <random>
#include <string>

#include "daemon/recording_support.hpp"

namespace selfsense::daemon {
namespace {

using testing::ScratchDir;
using testing::synthetic_sample;

std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(RecordingFile, AppearsOnlyOnceItHoldsARow) {
  const ScratchDir dir("rf-appears");
  const auto path = dir.path() / "a.csv";
  RecordingFile file(RowFormat(true), 4096);
  file.open(path, {"c"});
  file.add(synthetic_sample(0));
  EXPECT_FALSE(std::filesystem::exists(path));
  const RecordingFile::Result r = file.write_out();
  EXPECT_EQ(r.error, 0);
  EXPECT_EQ(r.rows_written, 1U);
  EXPECT_TRUE(std::filesystem::exists(path));
  EXPECT_TRUE(file.close().synced);

  // Opened and closed without a row: no file at all (a header-only file would not parse).
  const auto empty = dir.path() / "b.csv";
  file.open(empty, {"c"});
  file.close();
  EXPECT_FALSE(std::filesystem::exists(empty));
}

// Whatever the pattern of writes (many small ones force the re-written last row), no row
// straddles a 4096-byte boundary, so a write cut at a page boundary still ends at a row.
TEST(RecordingFile, EveryPageBoundaryIsARowBoundaryAndTheFileReadsBack) {
  const ScratchDir dir("rf-pages");
  const auto path = dir.path() / "pages.csv";
  RecordingFile file(RowFormat(true), 16384);
  file.open(path, {"page test"});
  std::mt19937 rng(7);
  constexpr int kRows = 20000;
  for (int i = 0; i < kRows; ++i) {
    file.add(synthetic_sample(i));
    if (file.write_due() || rng() % 13 == 0) {
      ASSERT_EQ(file.write_out().error, 0);
    }
  }
  ASSERT_EQ(file.close().error, 0);
  const std::string text = slurp(path);
  ASSERT_GT(text.size(), 40 * kFilePageBytes);
  for (std::size_t offset = kFilePageBytes; offset < text.size(); offset += kFilePageBytes)
    ASSERT_EQ(text[offset - 1], '\n') << "row straddles the page boundary at " << offset;
  EXPECT_EQ(text.back(), '\n');
  const io::Recording r = io::read_recording_csv(path);
  ASSERT_EQ(r.rows(), static_cast<std::size_t>(kRows));
  for (int i = 0; i < kRows; ++i)
    ASSERT_EQ(r.column("cycle")[static_cast<std::size_t>(i)], i);
  EXPECT_EQ(r.column("E")[123], synthetic_sample(123).e);  // full precision
}

TEST(RecordingFile, NamedPathThatExistsIsAnErrorAndTheRowsAreCountedLost) {
  const ScratchDir dir("rf-exists");
  const auto path = dir.path() / "taken.csv";
  std::ofstream(path) << "x\n";
  RecordingFile file(RowFormat(false), 4096);
  file.open(path, {});
  file.add(synthetic_sample(0));
  file.add(synthetic_sample(1));
  const RecordingFile::Result r = file.write_out();
  EXPECT_NE(r.error, 0);
  EXPECT_EQ(r.rows_lost, 2U);
  EXPECT_EQ(slurp(path), "x\n");
  file.close();
}

}  // namespace
}  // namespace selfsense::daemon
