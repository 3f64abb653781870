// Fuzz target: the recording CSV reader (io/recording.hpp) on any file content.
// Properties:
//  - a rejected file gives a RecordingError that starts with "FILE:LINE: " (only an empty file
//    or one of comments only, which have no line to name, may say "FILE: " alone), and no other
//    exception escapes;
//  - an accepted file holds at least one row, equal-length finite columns and a strictly
//    increasing t;
//  - it writes back (write_recording_csv) and reads back with the same comments, column names
//    and bit-identical values;
//  - without a required column t or E, the default read names the header's line.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <exception>
#include <string>

#include "fuzz_check.hpp"
#include "selfsense/io/recording.hpp"

namespace {

using selfsense::fuzz::require;
using selfsense::io::ReadOptions;
using selfsense::io::Recording;
using selfsense::io::RecordingError;

void check_rejection(const std::string& message, const std::string& file) {
  const bool whole_file = message == file + ": empty file: no header row" ||
                          message == file + ": no header row (only comment lines)";
  require(whole_file || selfsense::fuzz::names_file_and_line(message, file),
          "a rejected recording names the file and line", message);
}

void check_accepted(const Recording& r) {
  require(r.rows() > 0 && r.cols() > 0, "an accepted recording has rows and columns");
  for (std::size_t j = 0; j < r.cols(); ++j) {
    const auto column = r.column(j);
    require(column.size() == r.rows(), "columns have equal length", r.names()[j]);
    require(std::all_of(column.begin(), column.end(), [](double v) { return std::isfinite(v); }),
            "accepted values are finite", r.names()[j]);
  }
  if (r.has("t")) {
    const auto t = r.column("t");
    require(std::adjacent_find(t.begin(), t.end(), [](double a, double b) { return !(b > a); }) ==
                t.end(),
            "an accepted t strictly increases");
  }
}

void check_round_trip(const Recording& r, const selfsense::fuzz::ScratchFile& out) {
  try {
    selfsense::io::write_recording_csv(r, out.path());
  } catch (const std::exception& e) {
    selfsense::fuzz::violated("an accepted recording can be written", e.what());
  }
  Recording back;
  try {
    back = selfsense::io::read_recording_csv(out.path(), ReadOptions{{}});
  } catch (const std::exception& e) {
    selfsense::fuzz::violated("a written recording reads back", e.what());
  }
  require(back.comments == r.comments, "comments round-trip");
  require(back.names() == r.names(), "column names round-trip");
  require(back.rows() == r.rows(), "row count round-trips");
  for (std::size_t j = 0; j < r.cols(); ++j) {
    const auto a = r.column(j);
    const auto b = back.column(j);
    for (std::size_t i = 0; i < a.size(); ++i) {
      require(std::bit_cast<std::uint64_t>(a[i]) == std::bit_cast<std::uint64_t>(b[i]),
              "values round-trip bit for bit", r.names()[j] + "[" + std::to_string(i) + "]");
    }
  }
}

}  // namespace

// NOLINTNEXTLINE(readability-identifier-naming): the name libFuzzer calls.
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const selfsense::fuzz::ScratchFile input("in.csv");
  static const selfsense::fuzz::ScratchFile output("out.csv");
  input.write(selfsense::fuzz::as_text(data, size));
  const std::string file = input.path().string();

  Recording recording;
  try {
    recording = selfsense::io::read_recording_csv(input.path(), ReadOptions{{}});
  } catch (const RecordingError& e) {
    check_rejection(e.what(), file);
    return 0;
  } catch (const std::exception& e) {
    selfsense::fuzz::violated("only RecordingError leaves the reader", e.what());
  }
  check_accepted(recording);
  check_round_trip(recording, output);

  if (!recording.has("t") || !recording.has("E")) {
    try {
      static_cast<void>(selfsense::io::read_recording_csv(input.path()));
      selfsense::fuzz::violated("a recording without t or E is rejected by default", file);
    } catch (const RecordingError& e) {
      const std::string message = e.what();
      require(selfsense::fuzz::names_file_and_line(message, file) &&
                  message.find("missing required column") != std::string::npos,
              "a missing required column is named at the header's line", message);
    }
  }
  return 0;
}
