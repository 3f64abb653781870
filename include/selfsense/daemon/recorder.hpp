// The recorder: carries every loop sample from the real-time loop to disk (contract CSV
// recordings, rotated by size, crash-consistent) and to the flight recorder.
//
//   loop thread --push()--> SpscRing<LoopSample> --writer thread--> RecordingFile (when recording)
//                                                                \-> FlightRecorder (always)
//
// Threads:
//  - the loop (real-time) calls push() only: wait-free, no allocation, no lock, no system call.
//    A full ring refuses the sample and counts it as dropped (never silent).
//  - the writer thread (started by start()) pops in batches, formats rows, writes whole rows
//    with pwrite(2), fdatasyncs every flush period, rotates files past rotate_bytes, feeds the
//    flight recorder and makes its dumps. A write error (disk full) is counted and reported in
//    last_error(); the thread keeps running and tries again with the next rows.
//  - control threads (socket, signal handling, telemetry) call start_file(), stop_file(),
//    dump_flight(), current_path(), counters(), last_error(); these may block briefly (they
//    hand the request to the writer and wait for its answer) and never touch the loop.
// stop() drains the ring, closes the file (written and synced), writes a pending automatic
// flight dump and joins the writer: the SIGTERM path.
//
// Accounting. Once stopped (or after stop_file()), every sample push() was given is in exactly
// one of: samples_dropped (ring full), samples_unrecorded (no recording on), rows_written,
// rows_lost (write error), rows_bad_time (t not finite). samples_pushed + samples_dropped is
// what the loop offered.
//
// File names: DIRECTORY/PREFIX-YYYYmmddTHHMMSSZ-NNNN.csv, the time of start_file() and NNNN
// counting the files of that recording (rotations; also a t that fails to increase starts a
// new file, counted in time_breaks, so that every file keeps t strictly increasing).
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <thread>

#include "selfsense/daemon/flight_recorder.hpp"
#include "selfsense/daemon/recorder_config.hpp"
#include "selfsense/runtime/loop_sample.hpp"
#include "selfsense/runtime/spsc_ring.hpp"

namespace selfsense::daemon {

// A configuration that fails validate(), or a control request that cannot be carried out.
class RecorderError final : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct RecorderCounters {
  std::uint64_t samples_pushed{0};      // accepted by push()
  std::uint64_t samples_dropped{0};     // refused by push(): the ring was full
  std::uint64_t samples_consumed{0};    // taken from the ring by the writer
  std::uint64_t samples_unrecorded{0};  // taken while no recording was on
  std::uint64_t rows_written{0};        // rows that reached a file
  std::uint64_t rows_flushed{0};        // rows_written as of the last fdatasync
  std::uint64_t rows_lost{0};           // rows a write error kept out of the file
  std::uint64_t rows_bad_time{0};       // samples not written because t was not finite
  std::uint64_t time_breaks{0};         // a t that did not increase started a new file
  std::uint64_t files{0};               // recording files created
  std::uint64_t bytes_written{0};
  std::uint64_t flushes{0};          // successful fdatasyncs
  std::uint64_t write_errors{0};     // failed open, write, link, fdatasync
  std::uint64_t ring_high_water{0};  // most samples waiting in the ring at once
  std::uint64_t flight_dumps{0};
  std::uint64_t flight_dump_errors{0};
  bool recording{false};
};

class Recorder final {
 public:
  // Throws RecorderError listing every problem of validate(config). Allocates the ring, the
  // write buffer and the flight recorder's history; starts no thread.
  explicit Recorder(RecorderConfig config, FaultNamer fault_namer = {});
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;
  Recorder(Recorder&&) = delete;
  Recorder& operator=(Recorder&&) = delete;
  ~Recorder();

  void start();
  void stop();

  // Real-time safe (loop thread only).
  bool push(const runtime::LoopSample& sample) noexcept {
    if (ring_.try_push(sample)) return true;
    dropped_.store(dropped_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
    return false;
  }

  // Control side. A file starts after, and ends with, the last sample pushed before the call
  // (the writer first takes what was queued before it). start_file() returns the first file's path
  // (the file appears with its first rows); throws RecorderError when already recording or the
  // writer is not running.
  std::filesystem::path start_file();
  // Writes, syncs and closes the file; returns its path (nullopt when not recording).
  std::optional<std::filesystem::path> stop_file();
  [[nodiscard]] std::optional<std::filesystem::path> current_path() const;
  // Dumps the flight recorder to path (which must not exist); throws RecorderError on failure.
  FlightRecorder::Dump dump_flight(std::string_view reason, const std::filesystem::path& path);

  // Any thread.
  [[nodiscard]] RecorderCounters counters() const noexcept;
  [[nodiscard]] std::string last_error() const;
  [[nodiscard]] std::size_t queued() const noexcept { return ring_.size(); }
  [[nodiscard]] std::size_t capacity() const noexcept { return ring_.capacity(); }
  [[nodiscard]] const RecorderConfig& config() const noexcept { return config_; }

 private:
  struct Request;
  class Writer;

  std::string request(Request& request);

  RecorderConfig config_;
  runtime::SpscRing<runtime::LoopSample> ring_;
  std::atomic<std::uint64_t> dropped_{0};  // written by the loop thread only

  // Writer-owned state behind a pointer: the control side reaches it only through requests.
  std::unique_ptr<Writer> writer_;
  std::thread thread_{};

  mutable std::mutex mutex_{};  // guards the fields below
  std::condition_variable wake_writer_{};
  std::condition_variable request_done_{};
  Request* pending_{nullptr};
  bool stop_requested_{false};
  bool running_{false};
  std::optional<std::filesystem::path> current_path_{};
  std::string last_error_{};
  std::mutex control_mutex_{};  // one control request at a time
};

}  // namespace selfsense::daemon
