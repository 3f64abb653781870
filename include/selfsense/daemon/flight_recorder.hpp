// The flight recorder: the last seconds of loop samples kept in memory, written out as a contract
// recording when asked (dump) or when a sample shows a fault bit the one before it did not have
// (an automatic dump, made post_trigger_seconds later so that the file shows what followed).
//
// Fed by the recorder's writer thread with the samples it takes from the ring, so the loop pays
// nothing for it. Not thread-safe: one thread (that writer) calls everything; the Recorder hands
// control-side requests over to it. add() is noexcept and allocation-free (the history is
// allocated in the constructor); the dumps allocate and do file I/O.
//
// A dump is written like a recording (RecordingFile): it appears under its name only once
// complete, never overwrites an existing file, and holds the same columns. Rows whose t is not
// finite or does not increase are left out of a dump and counted in its header comment.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "selfsense/daemon/csv_row.hpp"
#include "selfsense/daemon/recorder_config.hpp"
#include "selfsense/runtime/loop_sample.hpp"

namespace selfsense::daemon {

// The name of fault bit `bit` (0..31) for file names; the daemon passes runtime::Fault's names.
using FaultNamer = std::function<std::string(unsigned bit)>;

class FlightRecorder final {
 public:
  struct Dump {
    std::filesystem::path path{};
    std::size_t rows{0};
    std::string error{};  // empty when the file was written
  };

  // Keeps ceil(config.seconds / sample_time_s) samples. default_directory takes automatic dumps
  // when config.directory is empty.
  FlightRecorder(const FlightRecorderConfig& config, const std::filesystem::path& default_directory,
                 double sample_time_s, bool references, FaultNamer fault_namer = {});
  // The same with the recording's columns (RowFormat: references, temperatures).
  FlightRecorder(const FlightRecorderConfig& config, const std::filesystem::path& default_directory,
                 double sample_time_s, RowFormat format, FaultNamer fault_namer = {});

  void add(const runtime::LoopSample& sample) noexcept;
  [[nodiscard]] std::size_t size() const noexcept { return count_; }
  [[nodiscard]] std::size_t capacity() const noexcept { return history_.size(); }

  [[nodiscard]] bool auto_dump_pending() const noexcept { return pending_; }
  [[nodiscard]] bool auto_dump_due() const noexcept {
    return pending_ && samples_after_trigger_ >= post_trigger_samples_;
  }
  // Writes the pending automatic dump now (due or not) to the automatic-dump directory.
  Dump dump_auto();
  // Writes the history to path (which must not exist), with the reason in its header.
  Dump dump(std::string_view reason, const std::filesystem::path& path);

  [[nodiscard]] std::uint64_t dumps() const noexcept { return dumps_; }
  [[nodiscard]] std::uint64_t dump_errors() const noexcept { return dump_errors_; }

 private:
  [[nodiscard]] std::string fault_names(std::uint32_t bits) const;
  Dump write(const std::filesystem::path& path, std::vector<std::string> comments);

  FlightRecorderConfig config_;
  std::filesystem::path directory_;
  double sample_time_s_{0.0};
  RowFormat format_{true};
  FaultNamer fault_namer_;
  std::vector<runtime::LoopSample> history_;
  std::size_t next_{0};
  std::size_t count_{0};
  std::uint32_t previous_faults_{0};
  bool pending_{false};
  std::uint32_t pending_bits_{0};
  std::int64_t trigger_cycle_{0};
  std::size_t samples_after_trigger_{0};
  std::size_t post_trigger_samples_{0};
  std::uint64_t dumps_{0};
  std::uint64_t dump_errors_{0};
};

}  // namespace selfsense::daemon
