#include "selfsense/daemon/recorder.hpp"

#include <mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "recorder_writer.hpp"

namespace selfsense::daemon {

namespace {

std::string validation_message(const RecorderConfig& config) {
  const std::vector<std::string> problems = validate(config);
  std::string message;
  for (const std::string& problem : problems) {
    if (!message.empty()) message += '\n';
    message += problem;
  }
  return message;
}

}  // namespace

Recorder::Recorder(RecorderConfig config, FaultNamer fault_namer)
    : config_(std::move(config)),
      ring_((validation_message(config_).empty() ? config_.ring_capacity : 2)) {
  if (const std::string problems = validation_message(config_); !problems.empty()) {
    throw RecorderError(problems);
  }
  writer_ = std::make_unique<Writer>(*this, std::move(fault_namer));
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
  thread_ = std::thread([this] { writer_->run(); });
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

}  // namespace selfsense::daemon
