// Fuzz target: the delimited-text importer (`selfsense import columns`) on any file content,
// with the map "1:t:ms,2:u:kV,3:q:nC,4:x:um" and a geometry, so the unit factors and the
// conversion to E, D and S run. The first byte picks the delimiter (',', ';', tab, blanks) and
// the header lines to skip (0..3); the rest is the file.
// Properties:
//  - a rejected file gives a RecordingError that starts with "FILE:LINE: ", or "FILE: " for the
//    problems of the whole file (empty, fewer than 2 rows), and no other exception escapes;
//  - an accepted file is a recording with t, E, D and S that write_recording_csv() writes and
//    read_recording_csv() reads back bit for bit: what the command writes is a valid recording.
#include <array>
#include <bit>
#include <cstdint>
#include <exception>
#include <string>
#include <string_view>

#include "fuzz_check.hpp"
#include "selfsense/importers/import_columns.hpp"

namespace {

using selfsense::fuzz::require;

selfsense::importers::ColumnsOptions options_for(std::uint8_t selector) {
  constexpr std::array<char, 4> kDelimiters = {',', ';', '\t', ' '};
  selfsense::importers::ColumnsOptions o;
  o.delimiter = kDelimiters.at(selector & 3U);
  o.skip_rows = (selector >> 2U) & 3U;
  o.map = selfsense::importers::parse_column_map("1:t:ms,2:u:kV,3:q:nC,4:x:um");
  o.layer_thickness_m = 1e-4;
  o.electrode_area_m2 = 1e-4;
  o.layers = 100.0;
  o.active_length_m = 0.01;
  return o;
}

bool whole_file_problem(const std::string& message, const std::string& file) {
  return message == file + ": empty file" ||
         message.starts_with(file + ": fewer than 2 data rows selected");
}

}  // namespace

// NOLINTNEXTLINE(readability-identifier-naming): the name libFuzzer calls.
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const selfsense::fuzz::ScratchFile input("in.txt");
  static const selfsense::fuzz::ScratchFile output("out.csv");
  if (size == 0) return 0;
  const selfsense::importers::ColumnsOptions options = options_for(data[0]);
  input.write(selfsense::fuzz::as_text(data + 1, size - 1));
  const std::string file = input.path().string();

  selfsense::io::Recording r;
  try {
    r = selfsense::importers::import_columns(input.path(), options);
  } catch (const selfsense::io::RecordingError& e) {
    require(
        whole_file_problem(e.what(), file) || selfsense::fuzz::names_file_and_line(e.what(), file),
        "a rejected text file names the file and line", e.what());
    return 0;
  } catch (const std::exception& e) {
    selfsense::fuzz::violated("only RecordingError leaves the columns importer", e.what());
  }
  for (const char* name : {"t", "E", "D", "S"})
    require(r.has(name), "an imported file has t, E, D and S", name);
  selfsense::io::Recording back;
  try {
    selfsense::io::write_recording_csv(r, output.path());
    back = selfsense::io::read_recording_csv(output.path());
  } catch (const std::exception& e) {
    selfsense::fuzz::violated("an imported file writes a valid recording", e.what());
  }
  require(back.names() == r.names() && back.comments == r.comments && back.rows() == r.rows(),
          "an imported recording reads back with the same columns and comments");
  for (std::size_t j = 0; j < r.cols(); ++j) {
    for (std::size_t i = 0; i < r.rows(); ++i) {
      require(std::bit_cast<std::uint64_t>(r.column(j)[i]) ==
                  std::bit_cast<std::uint64_t>(back.column(j)[i]),
              "an imported recording reads back bit for bit", r.names()[j]);
    }
  }
  return 0;
}
