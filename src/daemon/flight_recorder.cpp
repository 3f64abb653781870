#include "selfsense/daemon/flight_recorder.hpp"

#include <chrono>
#include <cmath>
#include <limits>
#include <system_error>
#include <utility>

#include "selfsense/daemon/recording_file.hpp"
#include "utc_stamp.hpp"

namespace selfsense::daemon {

namespace {

constexpr std::size_t kDumpChunkBytes = std::size_t{1} << 16U;

std::string hex(std::uint32_t bits) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string text = "0x";
  for (int shift = 28; shift >= 0; shift -= 4)
    text += kDigits[(bits >> static_cast<unsigned>(shift)) & 0xFU];
  return text;
}

// File names keep to A-Z a-z 0-9 - _ so that a fault name can never make a path.
std::string file_safe(const std::string& text) {
  std::string out;
  for (const char c : text) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '-' || c == '_';
    out += ok ? c : '_';
  }
  return out;
}

}  // namespace

FlightRecorder::FlightRecorder(const FlightRecorderConfig& config,
                               const std::filesystem::path& default_directory, double sample_time_s,
                               bool references, FaultNamer fault_namer)
    : FlightRecorder(config, default_directory, sample_time_s, RowFormat(references),
                     std::move(fault_namer)) {}

FlightRecorder::FlightRecorder(const FlightRecorderConfig& config,
                               const std::filesystem::path& default_directory, double sample_time_s,
                               RowFormat format, FaultNamer fault_namer)
    : config_(config),
      directory_(config.directory.empty() ? default_directory : config.directory),
      sample_time_s_(sample_time_s),
      format_(format),
      fault_namer_(std::move(fault_namer)),
      history_(static_cast<std::size_t>(std::ceil(config.seconds / sample_time_s))),
      post_trigger_samples_(
          static_cast<std::size_t>(std::llround(config.post_trigger_seconds / sample_time_s))) {}

void FlightRecorder::add(const runtime::LoopSample& sample) noexcept {
  history_[next_] = sample;
  next_ = next_ + 1 == history_.size() ? 0 : next_ + 1;
  if (count_ < history_.size()) ++count_;

  const std::uint32_t new_bits = sample.faults & ~previous_faults_;
  previous_faults_ = sample.faults;
  if (pending_) ++samples_after_trigger_;
  if (config_.dump_on_fault && new_bits != 0) {
    if (!pending_) {
      pending_ = true;
      pending_bits_ = 0;
      samples_after_trigger_ = 0;
      trigger_cycle_ = sample.cycle;
    }
    pending_bits_ |= new_bits;  // faults that follow before the dump go into the same file
  }
}

std::string FlightRecorder::fault_names(std::uint32_t bits) const {
  std::string names;
  for (unsigned bit = 0; bit < 32; ++bit) {
    if ((bits & (1U << bit)) == 0) continue;
    if (!names.empty()) names += '+';
    const std::string name = fault_namer_ ? fault_namer_(bit) : std::string();
    names += name.empty() ? "fault" + std::to_string(bit) : file_safe(name);
  }
  return names.empty() ? "none" : names;
}

FlightRecorder::Dump FlightRecorder::dump_auto() {
  const std::uint32_t bits = pending_bits_;
  const std::int64_t cycle = trigger_cycle_;
  pending_ = false;
  const std::string names = fault_names(bits);
  const auto now = std::chrono::system_clock::now();
  // The cycle makes the name unique even for two dumps within one second.
  const std::filesystem::path path =
      directory_ / (config_.prefix + "-" + detail::utc_stamp(now, true) + "-cycle" +
                    std::to_string(cycle) + "-" + names + ".csv");
  return write(path, {"reason: new fault " + names + " (" + hex(bits) + ") at cycle " +
                      std::to_string(cycle)});
}

FlightRecorder::Dump FlightRecorder::dump(std::string_view reason,
                                          const std::filesystem::path& path) {
  std::string text(reason);
  for (char& c : text) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  return write(path, {"reason: " + text});
}

FlightRecorder::Dump FlightRecorder::write(const std::filesystem::path& path,
                                           std::vector<std::string> comments) {
  Dump result;
  result.path = path;
  const std::size_t first = count_ < history_.size() ? 0 : next_;
  const auto at = [&](std::size_t i) -> const runtime::LoopSample& {
    return history_[(first + i) % history_.size()];
  };
  // The rows a contract reader accepts: finite t, strictly increasing.
  std::vector<bool> keep(count_, false);
  std::size_t kept = 0;
  double last_t = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < count_; ++i) {
    const double t = at(i).t;
    if (std::isfinite(t) && t > last_t) {
      keep[i] = true;
      last_t = t;
      ++kept;
    }
  }
  if (kept == 0) {
    result.error = "nothing to dump: the flight recorder holds no sample with a valid t";
    ++dump_errors_;
    return result;
  }
  std::error_code exists_error;
  if (std::filesystem::exists(path, exists_error)) {
    result.error = path.string() + ": exists; a dump never overwrites a file";
    ++dump_errors_;
    return result;
  }
  comments.insert(comments.begin(), "selfsense flight recorder dump written by selfsensed");
  comments.push_back("written_utc: " + detail::utc_stamp(std::chrono::system_clock::now(), false));
  comments.push_back("sample_time_s: " + std::to_string(sample_time_s_));
  comments.push_back("samples: " + std::to_string(kept) + " (history of " +
                     std::to_string(history_.size()) +
                     "); left out for a bad or repeated t: " + std::to_string(count_ - kept));

  RecordingFile file(format_, kDumpChunkBytes);
  file.open(path, comments);
  RecordingFile::Result outcome;
  for (std::size_t i = 0; i < count_ && outcome.error == 0; ++i) {
    if (!keep[i]) continue;
    file.add(at(i));
    if (file.write_due()) outcome = file.write_out();
  }
  const RecordingFile::Result closed = file.close();
  if (outcome.error == 0) outcome = closed;
  if (outcome.error != 0) {
    result.error = std::string(outcome.operation) + " " + path.string() + ": " +
                   std::generic_category().message(outcome.error);
    ++dump_errors_;
    return result;
  }
  result.rows = kept;
  ++dumps_;
  return result;
}

}  // namespace selfsense::daemon
