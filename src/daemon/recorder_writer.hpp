// The recorder's writer thread (include/selfsense/daemon/recorder.hpp): what it owns and its
// steps. Private to the daemon library; everything here runs on the writer thread except the
// counters, which any thread reads.
#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "selfsense/daemon/flight_recorder.hpp"
#include "selfsense/daemon/recorder.hpp"
#include "selfsense/daemon/recording_file.hpp"
#include "selfsense/runtime/loop_sample.hpp"

namespace selfsense::daemon {

// A control request handed to the writer (start_file, stop_file, dump_flight) and its answer.
struct Recorder::Request {
  enum class Kind { kStartFile, kStopFile, kDump };
  Kind kind{Kind::kStartFile};
  // Samples pushed before the request are handled as before it: a stopped file ends with, and
  // a started file begins after, the last sample pushed before the call.
  std::uint64_t pushed_before{0};
  std::string reason{};
  std::filesystem::path path{};
  bool done{false};
  std::string error{};
  std::optional<std::filesystem::path> result_path{};
  FlightRecorder::Dump dump{};
};

// One pass of run(): serve a pending request, drain a batch from the ring into the file and
// the flight recorder, flush when due, make a due automatic dump, then wait for more samples
// (or a request, or stop) unless the batch was full. The counters are atomics so that any
// thread can read them; the owner's mutex guards what control threads read (current path,
// last error) and the request hand-over.
class Recorder::Writer final {
 public:
  Writer(Recorder& owner, FaultNamer fault_namer);

  // The thread's body: until stop() was asked for and the ring is empty; then the file is
  // closed and a pending automatic flight dump written. Answers a request left pending.
  void run() noexcept;

  std::atomic<std::uint64_t> unrecorded{0};
  std::atomic<std::uint64_t> rows_written{0};
  std::atomic<std::uint64_t> rows_flushed{0};
  std::atomic<std::uint64_t> rows_lost{0};
  std::atomic<std::uint64_t> rows_bad_time{0};
  std::atomic<std::uint64_t> time_breaks{0};
  std::atomic<std::uint64_t> files{0};
  std::atomic<std::uint64_t> bytes{0};
  std::atomic<std::uint64_t> flushes{0};
  std::atomic<std::uint64_t> write_errors{0};
  std::atomic<std::uint64_t> high_water{0};
  std::atomic<std::uint64_t> dumps{0};
  std::atomic<std::uint64_t> dump_errors{0};
  std::atomic<bool> recording{false};

 private:
  // The steps of one pass.
  void serve_request();
  std::size_t drain_batch();
  void flush_if_due();
  void dump_auto();
  // True when the thread is to stop (asked to, and the ring is empty).
  bool wait_for_work();
  // After the loop: the file written and closed, the evidence of a fault dumped.
  void finish();
  // On the way out: no current file, not running, a pending request answered.
  void retire();

  // A request, after the samples pushed before it.
  void execute(Request& req);
  void start_file(Request& req);
  void stop_file(Request& req);
  void dump_flight(Request& req);

  // One sample to the flight recorder and, when recording, to the file.
  void consume(const runtime::LoopSample& s);
  [[nodiscard]] std::filesystem::path file_path(unsigned index) const;
  void open_next();
  void close_file();
  // Counts what a file operation did; a failure's text becomes the last error.
  void account(const RecordingFile::Result& r);
  void publish_dump_counts();
  void set_error(const std::string& text);
  void set_current_path(std::optional<std::filesystem::path> path);

  Recorder& owner_;
  const RecorderConfig& config_;
  std::chrono::steady_clock::duration flush_period_;
  RecordingFile file_;
  FlightRecorder flight_;
  std::vector<runtime::LoopSample> batch_;
  std::string session_stamp_{};
  std::string session_start_{};
  unsigned file_index_{0};
  bool counted_name_{false};
  std::chrono::steady_clock::time_point next_flush_{};
};

}  // namespace selfsense::daemon
