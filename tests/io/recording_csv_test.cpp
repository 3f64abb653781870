// Tests of the recording CSV reader and writer against the format in docs/recording-format.md.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <thread>
#include <vector>

#include "selfsense/io/recording.hpp"

namespace selfsense::io {
namespace {

namespace fs = std::filesystem;

// Every test works in its own directory; pid and test name keep parallel ctest runs apart.
class RecordingCsvTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("selfsense_io_test_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }

  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }

  [[nodiscard]] fs::path file(const std::string& name) const { return dir_ / name; }

  [[nodiscard]] fs::path write_text(const std::string& name, std::string_view text) const {
    fs::path path = file(name);
    std::ofstream out(path, std::ios::binary);
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    out.close();
    EXPECT_TRUE(out.good()) << "cannot write test input " << path;
    return path;
  }

  [[nodiscard]] static std::string read_text(const fs::path& path) {
    std::string text(static_cast<std::size_t>(fs::file_size(path)), '\0');
    std::ifstream in(path, std::ios::binary);
    in.read(text.data(), static_cast<std::streamsize>(text.size()));
    return text;
  }

 private:
  fs::path dir_;
};

// Runs action, expecting a RecordingError whose one-line message holds every one of parts.
template <typename Action>
void expect_error(Action&& action, std::initializer_list<std::string_view> parts) {
  try {
    action();
    ADD_FAILURE() << "no RecordingError thrown";
  } catch (const RecordingError& error) {
    const std::string message = error.what();
    EXPECT_EQ(message.find('\n'), std::string::npos) << "message is not one line: " << message;
    for (const std::string_view part : parts) {
      EXPECT_NE(message.find(part), std::string::npos)
          << "'" << part << "' missing from: " << message;
    }
  }
}

void expect_read_error(const fs::path& path, std::initializer_list<std::string_view> parts,
                       const ReadOptions& options = {}) {
  expect_error([&] { (void)read_recording_csv(path, options); }, parts);
}

std::vector<double> values(const Recording& recording, std::string_view name) {
  const auto column = recording.column(name);
  return {column.begin(), column.end()};
}

void expect_same_bits(const std::vector<double>& expected, std::span<const double> actual,
                      std::string_view name) {
  ASSERT_EQ(expected.size(), actual.size()) << name;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    ASSERT_EQ(std::bit_cast<std::uint64_t>(expected[i]), std::bit_cast<std::uint64_t>(actual[i]))
        << name << "[" << i << "]: wrote " << expected[i] << ", read " << actual[i];
  }
}

// ---------------------------------------------------------------------------------------------
// Recording

TEST(Recording, SetColumnAppendsAndReplaces) {
  Recording recording;
  EXPECT_EQ(recording.rows(), 0U);
  EXPECT_EQ(recording.cols(), 0U);

  recording.set_column("t", {0.0, 1.0, 2.0});
  recording.set_column("E", {5.0, 6.0, 7.0});
  EXPECT_EQ(recording.rows(), 3U);
  EXPECT_EQ(recording.cols(), 2U);
  EXPECT_EQ(recording.names(), (std::vector<std::string>{"t", "E"}));
  EXPECT_EQ(recording.index_of("E"), 1U);
  EXPECT_EQ(recording.index_of("D"), std::nullopt);
  EXPECT_TRUE(recording.has("t"));
  EXPECT_FALSE(recording.has("D"));

  recording.set_column("E", {8.0, 9.0, 10.0});
  EXPECT_EQ(recording.cols(), 2U);
  EXPECT_EQ(values(recording, "E"), (std::vector<double>{8.0, 9.0, 10.0}));
  EXPECT_EQ(recording.column(std::size_t{1})[2], 10.0);

  recording.column("E")[0] = -1.0;
  EXPECT_EQ(recording.column("E")[0], -1.0);
}

TEST(Recording, SetColumnRejectsWrongLength) {
  Recording recording;
  recording.set_column("t", {0.0, 1.0});
  EXPECT_THROW(recording.set_column("E", {1.0}), std::invalid_argument);
  EXPECT_THROW(recording.set_column("t", {0.0, 1.0, 2.0}), std::invalid_argument);
  EXPECT_EQ(recording.cols(), 1U);
  EXPECT_EQ(recording.rows(), 2U);
}

TEST(Recording, MissingColumnNamesIt) {
  Recording recording;
  recording.set_column("t", {0.0});
  const Recording& constant = recording;
  expect_error([&] { (void)recording.column("D"); }, {"no column 'D'"});
  expect_error([&] { (void)constant.column("S"); }, {"no column 'S'"});
  EXPECT_THROW((void)constant.column(std::size_t{3}), std::out_of_range);
}

// ---------------------------------------------------------------------------------------------
// Reading good files

TEST_F(RecordingCsvTest, ReadsCommentsHeaderAndRows) {
  const auto path = write_text("r.csv",
                               "# fs = 10 kHz\n"
                               "#no space\n"
                               "#  two spaces\n"
                               "#\n"
                               "t,E,D\n"
                               "0,1.5,-2e-3\n"
                               "0.5,-0,3\n");
  const Recording recording = read_recording_csv(path);
  EXPECT_EQ(recording.comments,
            (std::vector<std::string>{"fs = 10 kHz", "no space", " two spaces", ""}));
  EXPECT_EQ(recording.names(), (std::vector<std::string>{"t", "E", "D"}));
  EXPECT_EQ(recording.rows(), 2U);
  EXPECT_EQ(values(recording, "t"), (std::vector<double>{0.0, 0.5}));
  EXPECT_EQ(values(recording, "E"), (std::vector<double>{1.5, 0.0}));
  EXPECT_TRUE(std::signbit(recording.column("E")[1]));
  EXPECT_EQ(values(recording, "D"), (std::vector<double>{-2e-3, 3.0}));
}

TEST_F(RecordingCsvTest, AcceptsCrlfLineEndings) {
  const auto path = write_text("crlf.csv", "# rate\r\nt,E\r\n0,1\r\n1,2\r\n");
  const Recording recording = read_recording_csv(path);
  EXPECT_EQ(recording.comments, (std::vector<std::string>{"rate"}));
  EXPECT_EQ(recording.names(), (std::vector<std::string>{"t", "E"}));
  EXPECT_EQ(values(recording, "E"), (std::vector<double>{1.0, 2.0}));
}

TEST_F(RecordingCsvTest, AcceptsMissingFinalNewlineAndTrailingBlankLines) {
  for (const std::string_view text :
       {"t,E\n0,1\n1,2", "t,E\n0,1\n1,2\n\n\n", "t,E\r\n0,1\r\n1,2\r\n\r\n  \r\n\t"}) {
    SCOPED_TRACE(text);
    const Recording recording = read_recording_csv(write_text("end.csv", text));
    EXPECT_EQ(recording.rows(), 2U);
    EXPECT_EQ(values(recording, "E"), (std::vector<double>{1.0, 2.0}));
  }
}

TEST_F(RecordingCsvTest, SkipsUtf8ByteOrderMark) {
  const Recording recording = read_recording_csv(write_text("bom.csv", "\xEF\xBB\xBFt,E\n0,1\n"));
  EXPECT_EQ(recording.names(), (std::vector<std::string>{"t", "E"}));
}

TEST_F(RecordingCsvTest, ReadsFromAPipe) {
  // A FIFO cannot be mapped, so this takes the reader's fallback path.
  const auto path = file("pipe.csv");
  ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0);
  std::string text = "# piped\nt,E\n";
  for (int i = 0; i < 20000; ++i)
    text += std::to_string(i) + ",1.5\n";
  std::thread writer([&] {
    std::ofstream out(path, std::ios::binary);
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
  });
  const Recording recording = read_recording_csv(path);
  writer.join();
  EXPECT_EQ(recording.comments, (std::vector<std::string>{"piped"}));
  ASSERT_EQ(recording.rows(), 20000U);
  EXPECT_EQ(recording.column("t")[19999], 19999.0);
}

TEST_F(RecordingCsvTest, ColumnOrderIsFreeAndExtraColumnsAreCarried) {
  const auto in = write_text("in.csv",
                             "temp,E,my_probe,t,D\n"
                             "21.5,1,7,0,4\n"
                             "21.25,2,8,0.001,5\n");
  const Recording recording = read_recording_csv(in);
  EXPECT_EQ(recording.names(), (std::vector<std::string>{"temp", "E", "my_probe", "t", "D"}));
  EXPECT_EQ(values(recording, "t"), (std::vector<double>{0.0, 0.001}));
  EXPECT_EQ(values(recording, "my_probe"), (std::vector<double>{7.0, 8.0}));

  const auto out = file("out.csv");
  write_recording_csv(recording, out);
  const Recording again = read_recording_csv(out);
  EXPECT_EQ(again.names(), recording.names());
  for (const std::string& name : recording.names()) {
    EXPECT_EQ(values(again, name), values(recording, name)) << name;
  }
}

TEST_F(RecordingCsvTest, RequiredColumnsFollowTheOptions) {
  const auto path = write_text("d.csv", "t,D\n0,1\n");
  EXPECT_EQ(read_recording_csv(path, ReadOptions{.required = {"t", "D"}}).rows(), 1U);
  EXPECT_EQ(read_recording_csv(path, ReadOptions{.required = {}}).rows(), 1U);
}

TEST_F(RecordingCsvTest, TimeIsNotCheckedWhenAbsentAndNotRequired) {
  const auto path = write_text("no_t.csv", "E\n3\n1\n2\n");
  EXPECT_EQ(values(read_recording_csv(path, ReadOptions{.required = {"E"}}), "E"),
            (std::vector<double>{3.0, 1.0, 2.0}));
}

// ---------------------------------------------------------------------------------------------
// Writing

TEST_F(RecordingCsvTest, WritesCommentsHeaderAndShortestNumbers) {
  Recording recording;
  recording.comments = {"sample rate 10 kHz", "", " indented"};
  recording.set_column("t", {0.0, 0.1, 1e-7});
  recording.set_column("E", {-0.0, 1.0 / 3.0, 2.5e300});
  const auto path = file("w.csv");
  write_recording_csv(recording, path);
  EXPECT_EQ(read_text(path),
            "# sample rate 10 kHz\n"
            "#\n"
            "#  indented\n"
            "t,E\n"
            "0,-0\n"
            "0.1,0.3333333333333333\n"
            "1e-07,2.5e+300\n");
}

TEST_F(RecordingCsvTest, RoundTripIsBitExact) {
  constexpr std::size_t kRows = 5000;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::mt19937_64 rng(0x5e1f5e25U);

  // t walks through adjacent doubles: the closest values that must still read back distinct.
  std::vector<double> t(kRows);
  t[0] = -1.0;
  for (std::size_t i = 1; i < kRows; ++i)
    t[i] = std::nextafter(t[i - 1], kInf);

  // E: the awkward values first, then arbitrary finite bit patterns.
  using limits = std::numeric_limits<double>;
  std::vector<double> e = {0.0,
                           -0.0,
                           limits::denorm_min(),
                           -limits::denorm_min(),
                           std::nextafter(limits::min(), 0.0),
                           limits::min(),
                           -limits::min(),
                           limits::max(),
                           limits::lowest(),
                           limits::epsilon(),
                           0.1,
                           -1.0 / 3.0,
                           1e-300,
                           -1e300,
                           123456789.12345679,
                           9007199254740993.0};
  while (e.size() < kRows) {
    const double value = std::bit_cast<double>(rng());
    if (std::isfinite(value)) e.push_back(value);
  }

  // D: signed mantissas over the whole exponent range; S: values of a typical magnitude.
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-307, 307);
  std::vector<double> d(kRows);
  std::vector<double> s(kRows);
  for (std::size_t i = 0; i < kRows; ++i) {
    d[i] = unit(rng) * std::pow(10.0, exponent(rng));
    s[i] = unit(rng) * 1e-3;
  }

  Recording recording;
  recording.comments = {"round trip", "seed 0x5e1f5e25"};
  recording.set_column("E", e);
  recording.set_column("t", t);
  recording.set_column("D", d);
  recording.set_column("S", s);

  const auto first = file("first.csv");
  write_recording_csv(recording, first);
  const Recording read = read_recording_csv(first);
  EXPECT_EQ(read.comments, recording.comments);
  EXPECT_EQ(read.names(), recording.names());
  expect_same_bits(t, read.column("t"), "t");
  expect_same_bits(e, read.column("E"), "E");
  expect_same_bits(d, read.column("D"), "D");
  expect_same_bits(s, read.column("S"), "S");

  // Writing what was read gives the same bytes again.
  const auto second = file("second.csv");
  write_recording_csv(read, second);
  EXPECT_EQ(read_text(first), read_text(second));
}

TEST_F(RecordingCsvTest, WriteErrorsNameThePath) {
  Recording recording;
  recording.set_column("t", {0.0});
  recording.set_column("E", {1.0});

  const auto missing_dir = file("no_such_dir") / "out.csv";
  expect_error([&] { write_recording_csv(recording, missing_dir); },
               {missing_dir.string(), "cannot open"});

  if (fs::exists("/dev/full")) {
    expect_error([&] { write_recording_csv(recording, "/dev/full"); },
                 {"/dev/full", "cannot write"});
  }
}

TEST_F(RecordingCsvTest, WriterRefusesWhatCouldNotBeReadBack) {
  const auto path = write_text("keep.csv", "t,E\n0,1\n");
  const std::string before = read_text(path);

  Recording not_finite;
  not_finite.set_column("t", {0.0, 1.0, 2.0});
  not_finite.set_column("E", {1.0, 2.0, std::numeric_limits<double>::quiet_NaN()});
  not_finite.comments = {"one comment"};
  // Comment on line 1, header on line 2, the NaN in the third row: line 5.
  expect_error([&] { write_recording_csv(not_finite, path); },
               {"keep.csv:5:", "column 'E'", "nan"});
  // The first bad value in file order is named, whichever column it sits in.
  not_finite.set_column("D", {0.0, -std::numeric_limits<double>::infinity(), 0.0});
  expect_error([&] { write_recording_csv(not_finite, path); },
               {"keep.csv:4:", "column 'D'", "-inf"});

  Recording blank_name;
  blank_name.set_column(" ", {0.0});
  expect_error([&] { write_recording_csv(blank_name, path); }, {"keep.csv", "' '"});

  Recording comma_name;
  comma_name.set_column("t", {0.0});
  comma_name.set_column("a,b", {0.0});
  expect_error([&] { write_recording_csv(comma_name, path); }, {"keep.csv", "'a,b'"});

  Recording hash_first;
  hash_first.set_column("#t", {0.0});
  expect_error([&] { write_recording_csv(hash_first, path); }, {"keep.csv", "'#t'"});

  Recording broken_comment;
  broken_comment.set_column("t", {0.0});
  broken_comment.comments = {"fine", "two\nlines"};
  expect_error([&] { write_recording_csv(broken_comment, path); }, {"keep.csv", "comment 2"});

  expect_error([&] { write_recording_csv(Recording{}, path); }, {"keep.csv", "no columns"});

  // Refused before the file was opened, so it is untouched.
  EXPECT_EQ(read_text(path), before);
}

// ---------------------------------------------------------------------------------------------
// Reading bad files: each message names file, line and, where it applies, the column.

TEST_F(RecordingCsvTest, ErrorWhenFileCannotBeOpened) {
  const auto path = file("absent.csv");
  expect_read_error(path, {path.string(), "cannot open"});
}

TEST_F(RecordingCsvTest, ErrorWhenPathIsADirectory) {
  const auto path = file("a_directory.csv");
  fs::create_directory(path);
  expect_read_error(path, {"a_directory.csv", "cannot"});
}

TEST_F(RecordingCsvTest, ErrorWhenFileIsEmpty) {
  expect_read_error(write_text("empty.csv", ""), {"empty.csv", "empty file"});
  expect_read_error(write_text("blank.csv", "\n\r\n  \n"), {"blank.csv", "empty file"});
}

TEST_F(RecordingCsvTest, ErrorWhenThereIsNoHeader) {
  expect_read_error(write_text("comments.csv", "# only\n# comments\n"),
                    {"comments.csv", "no header"});
}

TEST_F(RecordingCsvTest, ErrorOnDuplicateColumnName) {
  expect_read_error(write_text("dup.csv", "# c\nt,E,D,E\n0,1,2,3\n"),
                    {"dup.csv:2:", "column 'E'", "duplicate"});
}

TEST_F(RecordingCsvTest, ErrorOnEmptyColumnName) {
  expect_read_error(write_text("hole.csv", "t,,E\n0,1,2\n"),
                    {"hole.csv:1:", "empty column name", "column 2"});
  expect_read_error(write_text("trailing.csv", "t,E,\n0,1,2\n"),
                    {"trailing.csv:1:", "empty column name", "column 3"});
}

// Found by fuzzing (tests/fuzz/corpus/recording_csv/regression-*): the reader took names and
// comments that the writer refuses, so an accepted file could not be written back.
TEST_F(RecordingCsvTest, ErrorOnBlankColumnNameOrCarriageReturnInsideALine) {
  expect_read_error(write_text("blank_name.csv", "t, ,E\n0,1,2\n"),
                    {"blank_name.csv:1:", "blank column name ' ' (column 2"});
  expect_read_error(write_text("cr_name.csv", "# c\nt,E\rx\n0,1\n"),
                    {"cr_name.csv:2:", "carriage return inside column name"});
  expect_read_error(write_text("cr_comment.csv", "# a\rb\nt,E\n0,1\n"),
                    {"cr_comment.csv:1:", "carriage return inside a comment"});
  // A CRLF line end is still only a line end.
  EXPECT_EQ(read_recording_csv(write_text("crlf.csv", "# a\r\nt,E\r\n0,1\r\n")).comments,
            (std::vector<std::string>{"a"}));
}

TEST_F(RecordingCsvTest, ErrorOnMissingRequiredColumn) {
  expect_read_error(write_text("no_e.csv", "# a\n# b\nt,D\n0,1\n"),
                    {"no_e.csv:3:", "column 'E'", "missing required", "t, D"});
  expect_read_error(write_text("no_t.csv", "E,D\n0,1\n"), {"no_t.csv:1:", "column 't'"});
  expect_read_error(write_text("no_d.csv", "t,E\n0,1\n"), {"no_d.csv:1:", "column 'D'"},
                    ReadOptions{.required = {"t", "E", "D"}});
}

TEST_F(RecordingCsvTest, ErrorOnWrongNumberOfCells) {
  expect_read_error(write_text("few.csv", "t,E,D\n0,1,2\n1,2\n"),
                    {"few.csv:3:", "expected 3", "found 2"});
  expect_read_error(write_text("many.csv", "t,E,D\n0,1,2\n1,2,3,4\n"),
                    {"many.csv:3:", "expected 3", "found 4"});
  expect_read_error(write_text("semicolon.csv", "t,E\n0;1\n"),
                    {"semicolon.csv:2:", "expected 2", "found 1"});
}

TEST_F(RecordingCsvTest, ErrorOnBadCells) {
  struct Case {
    std::string_view cell;
    std::string_view says;
  };
  for (const Case& bad :
       {Case{"abc", "not a number: 'abc'"}, Case{"", "empty cell"},
        Case{"1.5x", "not a number: '1.5x'"}, Case{" 1", "not a number: ' 1'"},
        Case{"1 ", "not a number: '1 '"}, Case{"1e", "not a number: '1e'"},
        Case{"0x10", "not a number: '0x10'"}, Case{"nan", "not a finite number: 'nan'"},
        Case{"NaN", "not a finite number: 'NaN'"}, Case{"inf", "not a finite number: 'inf'"},
        Case{"-infinity", "not a finite number: '-infinity'"},
        Case{"1e999", "out of the range of a double: '1e999'"},
        Case{"-2e308", "out of the range of a double: '-2e308'"},
        Case{"1e-400", "out of the range of a double: '1e-400'"}}) {
    SCOPED_TRACE(bad.cell);
    // The bad cell sits in E on line 4 (after a comment, the header and one good row).
    const std::string text = "# c\nt,E,D\n0,1,2\n1," + std::string(bad.cell) + ",3\n";
    expect_read_error(write_text("cell.csv", text), {"cell.csv:4:", "column 'E'", bad.says});
  }
}

TEST_F(RecordingCsvTest, ErrorOnBadCellInLastColumnWithCrlf) {
  expect_read_error(write_text("last.csv", "t,E\r\n0,1\r\n1,x\r\n"),
                    {"last.csv:3:", "column 'E'", "not a number: 'x'"});
}

TEST_F(RecordingCsvTest, ErrorQuotesLongCellsShortened) {
  const std::string junk(500, 'z');
  try {
    (void)read_recording_csv(write_text("long.csv", "t,E\n0," + junk + "\n"));
    ADD_FAILURE() << "no error";
  } catch (const RecordingError& error) {
    EXPECT_LT(std::string_view(error.what()).size(), 200U) << error.what();
  }
}

TEST_F(RecordingCsvTest, ErrorWhenTimeDoesNotIncrease) {
  expect_read_error(write_text("equal.csv", "t,E\n0,1\n0.5,1\n0.5,1\n"),
                    {"equal.csv:4:", "column 't'", "not strictly increasing", "0.5 after 0.5"});
  expect_read_error(write_text("back.csv", "E,t\n1,0\n1,0.25\n1,0.125\n"),
                    {"back.csv:4:", "column 't'", "0.125 after 0.25", "line 3"});
}

TEST_F(RecordingCsvTest, ErrorWhenThereAreNoRows) {
  expect_read_error(write_text("header_only.csv", "# c\nt,E\n"),
                    {"header_only.csv:2:", "no data rows"});
  expect_read_error(write_text("header_blank.csv", "t,E\r\n\r\n\r\n"),
                    {"header_blank.csv:1:", "no data rows"});
}

TEST_F(RecordingCsvTest, ErrorOnBlankLineInTheMiddle) {
  expect_read_error(write_text("gap.csv", "t,E\n0,1\n\n1,2\n"), {"gap.csv:3:", "blank line"});
  expect_read_error(write_text("gap_crlf.csv", "t,E\r\n0,1\r\n\r\n1,2\r\n"),
                    {"gap_crlf.csv:3:", "blank line"});
  expect_read_error(write_text("gap_head.csv", "# c\n\nt,E\n0,1\n"),
                    {"gap_head.csv:2:", "blank line"});
}

TEST_F(RecordingCsvTest, ErrorOnCommentAfterTheHeader) {
  expect_read_error(write_text("late.csv", "t,E\n0,1\n# late\n1,2\n"), {"late.csv:3:", "comment"});
}

}  // namespace
}  // namespace selfsense::io
