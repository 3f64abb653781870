// Fuzz target: the aixACCT "Export as ASCII" importer (`selfsense import aixacct`, block 1) on
// any file content.
// Properties:
//  - a rejected file gives a RecordingError that starts with "FILE:LINE: ", or "FILE: " for the
//    problems of the whole file (empty, no such block, no thickness or area), and no other
//    exception escapes;
//  - an accepted block is a recording with t, E, D and S that write_recording_csv() writes and
//    read_recording_csv() reads back with the same columns and values: what the command writes
//    is a valid recording.
#include <array>
#include <bit>
#include <cstdint>
#include <exception>
#include <string>
#include <string_view>

#include "fuzz_check.hpp"
#include "selfsense/importers/import_aixacct.hpp"

namespace {

using selfsense::fuzz::require;

bool whole_file_problem(const std::string& message, const std::string& file) {
  constexpr std::array<std::string_view, 4> kWholeFile = {": empty file", ": no data block ",
                                                          ": block 1 has no 'Thickness [nm]'",
                                                          ": block 1 has no 'Area [mm2]'"};
  for (const std::string_view what : kWholeFile) {
    if (message.starts_with(file + std::string(what))) return true;
  }
  return false;
}

}  // namespace

// NOLINTNEXTLINE(readability-identifier-naming): the name libFuzzer calls.
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const selfsense::fuzz::ScratchFile input("in.dat");
  static const selfsense::fuzz::ScratchFile output("out.csv");
  input.write(selfsense::fuzz::as_text(data, size));
  const std::string file = input.path().string();

  selfsense::importers::AixacctImport imported;
  try {
    imported =
        selfsense::importers::import_aixacct(input.path(), selfsense::importers::AixacctOptions{});
  } catch (const selfsense::io::RecordingError& e) {
    require(
        whole_file_problem(e.what(), file) || selfsense::fuzz::names_file_and_line(e.what(), file),
        "a rejected aixACCT file names the file and line", e.what());
    return 0;
  } catch (const std::exception& e) {
    selfsense::fuzz::violated("only RecordingError leaves the aixACCT importer", e.what());
  }
  const selfsense::io::Recording& r = imported.recording;
  for (const char* name : {"t", "E", "D", "S"})
    require(r.has(name), "an imported block has t, E, D and S", name);
  selfsense::io::Recording back;
  try {
    selfsense::io::write_recording_csv(r, output.path());
    back = selfsense::io::read_recording_csv(output.path());
  } catch (const std::exception& e) {
    selfsense::fuzz::violated("an imported block writes a valid recording", e.what());
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
