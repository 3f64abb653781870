#include "selfsense/daemon/recorder.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <span>
#include <system_error>
#include <utility>
#include <vector>

#include "selfsense/daemon/recording_file.hpp"
#include "utc_stamp.hpp"

#ifndef SELFSENSE_VERSION
#define SELFSENSE_VERSION "unknown"
#endif

namespace selfsense::daemon {

namespace {

// Rows are written once this much text is buffered (and at every flush): large writes, few
// system calls, and a buffer that stays in cache.
constexpr std::size_t kChunkBytes = std::size_t{1} << 16U;
// Samples taken from the ring at once.
constexpr std::size_t kBatch = 1024;
// How long the writer sleeps when the ring is empty. The loop never wakes it (that would be a
// system call on the real-time path); at 20 kHz 1 ms is 20 samples of a ring of thousands.
constexpr auto kIdleWait = std::chrono::milliseconds(1);

constexpr const char* kUnitsComment =
    "units: t s, E V/m, D C/m^2, T_hat Pa, S_hat -, setpoint S - (position) or T Pa (force), "
    "command V/m, S -, T Pa";
constexpr const char* kCodesComment =
    "codes: state 0 faulted 1 ready 2 armed; mode 0 position 1 force 2 open-loop 3 damping; "
    "nonfinite (value written as 0) E 1 D 2 T_hat 4 S_hat 8 setpoint 16 command 32 S 64 T 128";

std::string validation_message(const RecorderConfig& config) {
  const std::vector<std::string> problems = validate(config);
  std::string message;
  for (const std::string& problem : problems) {
    if (!message.empty()) message += '\n';
    message += problem;
  }
  return message;
}

template <typename Counter>
void add_to(Counter& counter, std::uint64_t n) noexcept {
  // One writer per counter: a load and a store, no read-modify-write needed.
  counter.store(counter.load(std::memory_order_relaxed) + n, std::memory_order_relaxed);
}

}  // namespace

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

// Everything the writer thread owns. The counters are atomics so that any thread can read them.
class Recorder::Writer {
 public:
  Writer(const RecorderConfig& config, FaultNamer fault_namer)
      : file(RowFormat(config.references), kChunkBytes),
        flight(config.flight, config.directory, config.sample_time_s, config.references,
               std::move(fault_namer)),
        batch(kBatch) {}

  RecordingFile file;
  FlightRecorder flight;
  std::vector<runtime::LoopSample> batch;
  std::string session_stamp{};
  std::string session_start{};
  unsigned file_index{0};
  bool counted_name{false};
  std::chrono::steady_clock::time_point next_flush{};

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
};

Recorder::Recorder(RecorderConfig config, FaultNamer fault_namer)
    : config_(std::move(config)),
      ring_((validation_message(config_).empty() ? config_.ring_capacity : 2)) {
  if (const std::string problems = validation_message(config_); !problems.empty()) {
    throw RecorderError(problems);
  }
  writer_ = std::make_unique<Writer>(config_, std::move(fault_namer));
}

Recorder::~Recorder() {
  stop();
}

void Recorder::start() {
  {
    const std::lock_guard lock(mutex_);
    if (running_) return;
    running_ = true;
    stop_requested_ = false;
  }
  thread_ = std::thread([this] { run(); });
}

void Recorder::stop() {
  {
    const std::lock_guard lock(mutex_);
    stop_requested_ = true;
  }
  wake_writer_.notify_all();
  if (thread_.joinable()) thread_.join();
}

std::string Recorder::request(Request& req) {
  const std::lock_guard serial(control_mutex_);
  std::unique_lock lock(mutex_);
  if (!running_ || stop_requested_)
    throw RecorderError("recorder: the writer thread is not running");
  req.pushed_before = ring_.pushed_total();
  pending_ = &req;
  wake_writer_.notify_all();
  request_done_.wait(lock, [&req] { return req.done; });
  return req.error;
}

std::filesystem::path Recorder::start_file() {
  Request req;
  req.kind = Request::Kind::kStartFile;
  if (std::string error = request(req); !error.empty()) throw RecorderError(error);
  return *req.result_path;
}

std::optional<std::filesystem::path> Recorder::stop_file() {
  Request req;
  req.kind = Request::Kind::kStopFile;
  if (std::string error = request(req); !error.empty()) throw RecorderError(error);
  return req.result_path;
}

FlightRecorder::Dump Recorder::dump_flight(std::string_view reason,
                                           const std::filesystem::path& path) {
  Request req;
  req.kind = Request::Kind::kDump;
  req.reason = std::string(reason);
  req.path = path;
  if (std::string error = request(req); !error.empty()) throw RecorderError(error);
  return req.dump;
}

std::optional<std::filesystem::path> Recorder::current_path() const {
  const std::lock_guard lock(mutex_);
  return current_path_;
}

std::string Recorder::last_error() const {
  const std::lock_guard lock(mutex_);
  return last_error_;
}

RecorderCounters Recorder::counters() const noexcept {
  const Writer& w = *writer_;
  constexpr auto kRelaxed = std::memory_order_relaxed;
  RecorderCounters c;
  c.samples_pushed = ring_.pushed_total();
  c.samples_dropped = dropped_.load(kRelaxed);
  c.samples_consumed = ring_.popped_total();
  c.samples_unrecorded = w.unrecorded.load(kRelaxed);
  c.rows_written = w.rows_written.load(kRelaxed);
  c.rows_flushed = w.rows_flushed.load(kRelaxed);
  c.rows_lost = w.rows_lost.load(kRelaxed);
  c.rows_bad_time = w.rows_bad_time.load(kRelaxed);
  c.time_breaks = w.time_breaks.load(kRelaxed);
  c.files = w.files.load(kRelaxed);
  c.bytes_written = w.bytes.load(kRelaxed);
  c.flushes = w.flushes.load(kRelaxed);
  c.write_errors = w.write_errors.load(kRelaxed);
  c.ring_high_water = w.high_water.load(kRelaxed);
  c.flight_dumps = w.dumps.load(kRelaxed);
  c.flight_dump_errors = w.dump_errors.load(kRelaxed);
  c.recording = w.recording.load(kRelaxed);
  return c;
}

// ---------------------------------------------------------------------------------------------
// The writer thread. Everything below runs on it.

void Recorder::run() noexcept {
  Writer& w = *writer_;
  const auto flush_period = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double, std::milli>(config_.flush_period_ms));

  const auto set_error = [this](const std::string& text) {
    const std::lock_guard lock(mutex_);
    last_error_ = text;
  };
  const auto account = [&](const RecordingFile::Result& r) {
    add_to(w.rows_written, r.rows_written);
    add_to(w.rows_lost, r.rows_lost);
    add_to(w.bytes, r.bytes_written);
    if (r.synced) {
      add_to(w.flushes, 1);
      w.rows_flushed.store(w.rows_written.load(std::memory_order_relaxed),
                           std::memory_order_relaxed);
    }
    if (w.file.named() && !w.counted_name) {
      w.counted_name = true;
      add_to(w.files, 1);
    }
    if (r.error != 0) {
      // The message first: whoever sees the count (the status, a test) then finds its text.
      set_error(std::string(r.operation) + " " + w.file.path().string() + ": " +
                std::generic_category().message(r.error));
      add_to(w.write_errors, 1);
    }
  };
  const auto file_path = [&](unsigned index) {
    std::string number = std::to_string(index);
    number.insert(0, number.size() < 4 ? 4 - number.size() : 0, '0');
    return config_.directory / (config_.prefix + "-" + w.session_stamp + "-" + number + ".csv");
  };
  const auto open_next = [&] {
    std::filesystem::path path;
    std::error_code error;
    do {
      path = file_path(++w.file_index);
    } while (std::filesystem::exists(path, error));
    std::vector<std::string> comments;
    comments.emplace_back("selfsense recording written by selfsensed's recorder (selfsense " +
                          std::string(SELFSENSE_VERSION) + ")");
    comments.push_back("start_time_utc: " + w.session_start);
    comments.push_back("file: " + std::to_string(w.file_index) +
                       (w.file_index > 1 ? " (rows continue from the previous file)" : ""));
    comments.push_back("sample_time_s: " + std::to_string(config_.sample_time_s));
    comments.emplace_back(kUnitsComment);
    comments.emplace_back(kCodesComment);
    comments.insert(comments.end(), config_.comments.begin(), config_.comments.end());
    w.file.open(path, comments);
    w.counted_name = false;
    const std::lock_guard lock(mutex_);
    current_path_ = path;
  };
  const auto close_file = [&] {
    account(w.file.close());
    w.recording.store(false, std::memory_order_relaxed);
  };
  const auto consume = [&](const runtime::LoopSample& s) {
    w.flight.add(s);
    if (!w.file.is_open()) {
      add_to(w.unrecorded, 1);
      return;
    }
    if (!std::isfinite(s.t)) {
      add_to(w.rows_bad_time, 1);
      return;
    }
    if (w.file.has_rows()) {
      const bool time_break = !(s.t > w.file.last_t());
      if (time_break) add_to(w.time_breaks, 1);
      if (time_break || w.file.bytes() + 2 * kMaxRowBytes > config_.rotate_bytes) {
        account(w.file.close());
        open_next();
      }
    }
    w.file.add(s);
    if (w.file.write_due()) account(w.file.write_out());
  };
  const auto dump_auto = [&] {
    const FlightRecorder::Dump dump = w.flight.dump_auto();
    w.dumps.store(w.flight.dumps(), std::memory_order_relaxed);
    w.dump_errors.store(w.flight.dump_errors(), std::memory_order_relaxed);
    if (!dump.error.empty()) set_error("flight recorder: " + dump.error);
  };
  const auto execute = [&](Request& req) {
    switch (req.kind) {
      case Request::Kind::kStartFile:
        if (w.file.is_open()) {
          req.error = "already recording to " + w.file.path().string();
          return;
        }
        if (!std::filesystem::is_directory(config_.directory)) {
          req.error = "recorder.directory: " + config_.directory.string() + " is not a directory";
          return;
        }
        w.session_stamp = detail::utc_stamp(std::chrono::system_clock::now(), true);
        w.session_start = detail::utc_stamp(std::chrono::system_clock::now(), false);
        w.file_index = 0;
        open_next();
        w.recording.store(true, std::memory_order_relaxed);
        w.next_flush = std::chrono::steady_clock::now() + flush_period;
        req.result_path = w.file.path();
        return;
      case Request::Kind::kStopFile:
        if (!w.file.is_open()) return;
        req.result_path = w.file.path();
        close_file();
        {
          const std::lock_guard lock(mutex_);
          current_path_.reset();
        }
        return;
      case Request::Kind::kDump:
        req.dump = w.flight.dump(req.reason, req.path);
        w.dumps.store(w.flight.dumps(), std::memory_order_relaxed);
        w.dump_errors.store(w.flight.dump_errors(), std::memory_order_relaxed);
        req.error = req.dump.error;
        return;
    }
  };
  const auto serve = [&] {
    Request* req = nullptr;
    {
      const std::lock_guard lock(mutex_);
      req = pending_;
    }
    if (req == nullptr) return;
    try {
      while (ring_.popped_total() < req->pushed_before) {
        const auto want = static_cast<std::size_t>(
            std::min<std::uint64_t>(w.batch.size(), req->pushed_before - ring_.popped_total()));
        const std::size_t n = ring_.pop_into(std::span(w.batch.data(), want));
        for (std::size_t i = 0; i < n; ++i)
          consume(w.batch[i]);
      }
      execute(*req);
    } catch (const std::exception& e) {
      req->error = e.what();
    }
    const std::lock_guard lock(mutex_);
    req->done = true;
    pending_ = nullptr;
    request_done_.notify_all();
  };

  try {
    while (true) {
      serve();
      const std::size_t n = ring_.pop_into(w.batch);
      const std::uint64_t waiting = n + ring_.size();
      if (waiting > w.high_water.load(std::memory_order_relaxed)) {
        w.high_water.store(waiting, std::memory_order_relaxed);
      }
      for (std::size_t i = 0; i < n; ++i)
        consume(w.batch[i]);
      if (w.file.is_open() && std::chrono::steady_clock::now() >= w.next_flush) {
        account(w.file.write_out());
        account(w.file.sync());
        w.next_flush = std::chrono::steady_clock::now() + flush_period;
      }
      if (w.flight.auto_dump_due()) dump_auto();
      if (n == w.batch.size()) continue;
      std::unique_lock lock(mutex_);
      if (stop_requested_ && ring_.size() == 0) break;
      wake_writer_.wait_for(lock, kIdleWait,
                            [this] { return pending_ != nullptr || stop_requested_; });
    }
    // Stopping: the ring is empty; finish the file and the evidence of a fault.
    if (w.file.is_open()) close_file();
    if (w.flight.auto_dump_pending()) dump_auto();
  } catch (const std::exception& e) {
    set_error(std::string("recorder writer stopped: ") + e.what());
  }
  const std::lock_guard lock(mutex_);
  current_path_.reset();
  running_ = false;
  if (pending_ != nullptr) {
    pending_->error = "recorder: the writer thread stopped";
    pending_->done = true;
    pending_ = nullptr;
    request_done_.notify_all();
  }
}

}  // namespace selfsense::daemon
