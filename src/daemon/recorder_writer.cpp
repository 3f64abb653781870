#include "recorder_writer.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <mutex>
#include <span>
#include <system_error>
#include <utility>

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
    "command V/m, S -, T Pa, temp degC, temp_equivalent degC";
constexpr const char* kCodesComment =
    "codes: state 0 faulted 1 ready 2 armed; mode 0 position 1 force 2 open-loop 3 damping; "
    "nonfinite (value written as 0) E 1 D 2 T_hat 4 S_hat 8 setpoint 16 command 32 S 64 T 128 "
    "temp 256 temp_equivalent 512";

RowFormat row_format(const RecorderConfig& c) noexcept {
  return {c.references, c.temperature, c.temperature_equivalent};
}

template <typename Counter>
void add_to(Counter& counter, std::uint64_t n) noexcept {
  // One writer per counter: a load and a store, no read-modify-write needed.
  counter.store(counter.load(std::memory_order_relaxed) + n, std::memory_order_relaxed);
}

}  // namespace

Recorder::Writer::Writer(Recorder& owner, FaultNamer fault_namer)
    : owner_(owner),
      config_(owner.config_),
      flush_period_(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
          std::chrono::duration<double, std::milli>(config_.flush_period_ms))),
      file_(row_format(config_), kChunkBytes),
      flight_(config_.flight, config_.directory, config_.sample_time_s, row_format(config_),
              std::move(fault_namer)),
      batch_(kBatch) {}

void Recorder::Writer::run() noexcept {
  try {
    while (true) {
      serve_request();
      const std::size_t n = drain_batch();
      flush_if_due();
      if (flight_.auto_dump_due()) dump_auto();
      if (n == batch_.size()) continue;
      if (wait_for_work()) break;
    }
    finish();
  } catch (const std::exception& e) {
    set_error(std::string("recorder writer stopped: ") + e.what());
  }
  retire();
}

// ---- the steps of one pass ---------------------------------------------------------------------

void Recorder::Writer::serve_request() {
  Request* req = nullptr;
  {
    const std::lock_guard lock(owner_.mutex_);
    req = owner_.pending_;
  }
  if (req == nullptr) return;
  try {
    while (owner_.ring_.popped_total() < req->pushed_before) {
      const auto want = static_cast<std::size_t>(
          std::min<std::uint64_t>(batch_.size(), req->pushed_before - owner_.ring_.popped_total()));
      const std::size_t n = owner_.ring_.pop_into(std::span(batch_.data(), want));
      for (std::size_t i = 0; i < n; ++i)
        consume(batch_[i]);
    }
    execute(*req);
  } catch (const std::exception& e) {
    req->error = e.what();
  }
  const std::lock_guard lock(owner_.mutex_);
  req->done = true;
  owner_.pending_ = nullptr;
  owner_.request_done_.notify_all();
}

std::size_t Recorder::Writer::drain_batch() {
  const std::size_t n = owner_.ring_.pop_into(batch_);
  const std::uint64_t waiting = n + owner_.ring_.size();
  if (waiting > high_water.load(std::memory_order_relaxed)) {
    high_water.store(waiting, std::memory_order_relaxed);
  }
  for (std::size_t i = 0; i < n; ++i)
    consume(batch_[i]);
  return n;
}

void Recorder::Writer::flush_if_due() {
  if (!file_.is_open() || std::chrono::steady_clock::now() < next_flush_) return;
  account(file_.write_out());
  account(file_.sync());
  next_flush_ = std::chrono::steady_clock::now() + flush_period_;
}

void Recorder::Writer::dump_auto() {
  const FlightRecorder::Dump dump = flight_.dump_auto();
  publish_dump_counts();
  if (!dump.error.empty()) set_error("flight recorder: " + dump.error);
}

bool Recorder::Writer::wait_for_work() {
  std::unique_lock lock(owner_.mutex_);
  if (owner_.stop_requested_ && owner_.ring_.size() == 0) return true;
  owner_.wake_writer_.wait_for(
      lock, kIdleWait, [this] { return owner_.pending_ != nullptr || owner_.stop_requested_; });
  return false;
}

void Recorder::Writer::finish() {
  if (file_.is_open()) close_file();
  if (flight_.auto_dump_pending()) dump_auto();
}

void Recorder::Writer::retire() {
  const std::lock_guard lock(owner_.mutex_);
  owner_.current_path_.reset();
  owner_.running_ = false;
  if (owner_.pending_ != nullptr) {
    owner_.pending_->error = "recorder: the writer thread stopped";
    owner_.pending_->done = true;
    owner_.pending_ = nullptr;
    owner_.request_done_.notify_all();
  }
}

// ---- requests ----------------------------------------------------------------------------------

void Recorder::Writer::execute(Request& req) {
  switch (req.kind) {
    case Request::Kind::kStartFile:
      start_file(req);
      return;
    case Request::Kind::kStopFile:
      stop_file(req);
      return;
    case Request::Kind::kDump:
      dump_flight(req);
      return;
  }
}

void Recorder::Writer::start_file(Request& req) {
  if (file_.is_open()) {
    req.error = "already recording to " + file_.path().string();
    return;
  }
  if (!std::filesystem::is_directory(config_.directory)) {
    req.error = "recorder.directory: " + config_.directory.string() + " is not a directory";
    return;
  }
  session_stamp_ = detail::utc_stamp(std::chrono::system_clock::now(), true);
  session_start_ = detail::utc_stamp(std::chrono::system_clock::now(), false);
  file_index_ = 0;
  open_next();
  recording.store(true, std::memory_order_relaxed);
  next_flush_ = std::chrono::steady_clock::now() + flush_period_;
  req.result_path = file_.path();
}

void Recorder::Writer::stop_file(Request& req) {
  if (!file_.is_open()) return;
  req.result_path = file_.path();
  close_file();
  set_current_path(std::nullopt);
}

void Recorder::Writer::dump_flight(Request& req) {
  req.dump = flight_.dump(req.reason, req.path);
  publish_dump_counts();
  req.error = req.dump.error;
}

// ---- samples and files -------------------------------------------------------------------------

void Recorder::Writer::consume(const runtime::LoopSample& s) {
  flight_.add(s);
  if (!file_.is_open()) {
    add_to(unrecorded, 1);
    return;
  }
  if (!std::isfinite(s.t)) {
    add_to(rows_bad_time, 1);
    return;
  }
  if (file_.has_rows()) {
    const bool time_break = !(s.t > file_.last_t());
    if (time_break) add_to(time_breaks, 1);
    if (time_break || file_.bytes() + 2 * kMaxRowBytes > config_.rotate_bytes) {
      account(file_.close());
      open_next();
    }
  }
  file_.add(s);
  if (file_.write_due()) account(file_.write_out());
}

std::filesystem::path Recorder::Writer::file_path(unsigned index) const {
  std::string number = std::to_string(index);
  number.insert(0, number.size() < 4 ? 4 - number.size() : 0, '0');
  return config_.directory / (config_.prefix + "-" + session_stamp_ + "-" + number + ".csv");
}

void Recorder::Writer::open_next() {
  std::filesystem::path path;
  std::error_code error;
  do {
    path = file_path(++file_index_);
  } while (std::filesystem::exists(path, error));
  std::vector<std::string> comments;
  comments.emplace_back("selfsense recording written by selfsensed's recorder (selfsense " +
                        std::string(SELFSENSE_VERSION) + ")");
  comments.push_back("start_time_utc: " + session_start_);
  comments.push_back("file: " + std::to_string(file_index_) +
                     (file_index_ > 1 ? " (rows continue from the previous file)" : ""));
  comments.push_back("sample_time_s: " + std::to_string(config_.sample_time_s));
  comments.emplace_back(kUnitsComment);
  comments.emplace_back(kCodesComment);
  comments.insert(comments.end(), config_.comments.begin(), config_.comments.end());
  file_.open(path, comments);
  counted_name_ = false;
  set_current_path(path);
}

void Recorder::Writer::close_file() {
  account(file_.close());
  recording.store(false, std::memory_order_relaxed);
}

void Recorder::Writer::account(const RecordingFile::Result& r) {
  add_to(rows_written, r.rows_written);
  add_to(rows_lost, r.rows_lost);
  add_to(bytes, r.bytes_written);
  if (r.synced) {
    add_to(flushes, 1);
    rows_flushed.store(rows_written.load(std::memory_order_relaxed), std::memory_order_relaxed);
  }
  if (file_.named() && !counted_name_) {
    counted_name_ = true;
    add_to(files, 1);
  }
  if (r.error != 0) {
    // The message first: whoever sees the count (the status, a test) then finds its text.
    set_error(std::string(r.operation) + " " + file_.path().string() + ": " +
              std::generic_category().message(r.error));
    add_to(write_errors, 1);
  }
}

void Recorder::Writer::publish_dump_counts() {
  dumps.store(flight_.dumps(), std::memory_order_relaxed);
  dump_errors.store(flight_.dump_errors(), std::memory_order_relaxed);
}

void Recorder::Writer::set_error(const std::string& text) {
  const std::lock_guard lock(owner_.mutex_);
  owner_.last_error_ = text;
}

void Recorder::Writer::set_current_path(std::optional<std::filesystem::path> path) {
  const std::lock_guard lock(owner_.mutex_);
  owner_.current_path_ = std::move(path);
}

}  // namespace selfsense::daemon
