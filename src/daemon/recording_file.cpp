#include "selfsense/daemon/recording_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cassert>
#include <cerrno>
#include <cstring>
#include <string>
#include <utility>

namespace selfsense::daemon {

namespace {

constexpr mode_t kFileMode = 0644;

// Writes all of text at offset, looping over short writes; returns 0 or the errno that stopped
// it. written: how many bytes reached the file.
int write_all(int fd, const char* text, std::size_t size, std::size_t offset,
              std::size_t& written) noexcept {
  written = 0;
  while (written < size) {
    const ssize_t n =
        ::pwrite(fd, text + written, size - written, static_cast<off_t>(offset + written));
    if (n < 0) {
      if (errno == EINTR) continue;
      return errno;
    }
    if (n == 0) return EIO;
    written += static_cast<std::size_t>(n);
  }
  return 0;
}

void merge(RecordingFile::Result& into, const RecordingFile::Result& from) noexcept {
  into.rows_written += from.rows_written;
  into.rows_lost += from.rows_lost;
  into.bytes_written += from.bytes_written;
  into.synced = into.synced || from.synced;
  if (from.error != 0) {
    into.error = from.error;
    into.operation = from.operation;
  }
}

}  // namespace

RecordingFile::RecordingFile(RowFormat format, std::size_t chunk_bytes)
    : format_(format), chunk_bytes_(chunk_bytes) {
  // Room for a chunk, the header block, a re-written last row and the padding of a page.
  buffer_.resize(chunk_bytes_ + 2 * kFilePageBytes + 4 * kMaxRowBytes);
  last_row_.resize(2 * kMaxRowBytes);
}

RecordingFile::~RecordingFile() {
  if (open_) close();
}

void RecordingFile::open(std::filesystem::path path, const std::vector<std::string>& comments) {
  if (open_) close();
  path_ = std::move(path);
  header_ = format_.header_block(comments);
  // Rows must fit beside the header in the first page (RecorderConfig limits the comments).
  assert(header_.size() + 2 * kMaxRowBytes <= kFilePageBytes);
  open_ = true;
  named_ = false;
  dirty_ = false;
  dir_synced_ = false;
  rows_on_disk_ = 0;
  last_t_ = 0.0;
  last_row_length_ = 0;
  reset_buffer_to_header();
}

void RecordingFile::reset_buffer_to_header() noexcept {
  std::memcpy(buffer_.data(), header_.data(), header_.size());
  used_ = header_.size();
  buffer_start_ = 0;
  committed_ = 0;
  buffer_has_row_ = false;
  rewrite_ = false;
  rows_buffered_ = 0;
}

void RecordingFile::keep_last_row(std::size_t start_in_buffer, std::size_t length) noexcept {
  std::memcpy(last_row_.data(), buffer_.data() + start_in_buffer, length);
  last_row_start_ = buffer_start_ + start_in_buffer;
  last_row_length_ = length;
}

void RecordingFile::add(const runtime::LoopSample& sample) noexcept {
  assert(open_);
  if (used_ + kFilePageBytes + 2 * kMaxRowBytes > buffer_.size()) {
    // The caller did not write when write_due(); keep the rows anyway.
    carry_ = write_out();
  }
  std::array<char, kMaxRowBytes> row{};
  const std::size_t length = format_.format(sample, row.data());
  const std::size_t offset = buffer_start_ + used_;
  const std::size_t room = kFilePageBytes - offset % kFilePageBytes;
  if (length > room) {
    // The row would straddle a page boundary: lengthen the row before it to end there.
    if (buffer_has_row_) {
      used_ = buffer_last_row_ +
              RowFormat::pad(buffer_.data() + buffer_last_row_, used_ - buffer_last_row_, room);
    } else if (last_row_length_ > 0 && used_ == 0) {
      std::memcpy(buffer_.data(), last_row_.data(), last_row_length_);
      used_ = RowFormat::pad(buffer_.data(), last_row_length_, room);
      buffer_start_ = last_row_start_;
      buffer_last_row_ = 0;
      buffer_has_row_ = true;
      rewrite_ = true;
    }
    // Otherwise only the header precedes it, which open() keeps well inside the first page.
  }
  std::memcpy(buffer_.data() + used_, row.data(), length);
  buffer_last_row_ = used_;
  buffer_has_row_ = true;
  used_ += length;
  ++rows_buffered_;
  last_t_ = sample.t;
}

RecordingFile::Result RecordingFile::create_file() noexcept {
  Result result;
  const std::filesystem::path dir = path_.parent_path().empty() ? "." : path_.parent_path();
  fd_ = ::open(dir.c_str(), O_TMPFILE | O_WRONLY | O_CLOEXEC, kFileMode);
  if (fd_ >= 0) return result;
  if (errno != EOPNOTSUPP && errno != EISDIR && errno != EINVAL) {
    result.error = errno;
    result.operation = "open";
    return result;
  }
  // No O_TMPFILE here: create the named file right before its first write.
  fd_ = ::open(path_.c_str(), O_CREAT | O_EXCL | O_WRONLY | O_CLOEXEC, kFileMode);
  if (fd_ < 0) {
    result.error = errno;
    result.operation = "open";
    return result;
  }
  named_ = true;
  return result;
}

void RecordingFile::fail_write(Result& result, int error, const char* operation) noexcept {
  result.error = error;
  result.operation = operation;
  result.rows_lost += rows_buffered_;
  if (fd_ >= 0 && !named_) {
    // Nothing reachable was written: drop the unnamed file and start over with the header.
    ::close(fd_);
    fd_ = -1;
    rows_on_disk_ = 0;
    last_row_length_ = 0;
    reset_buffer_to_header();
    return;
  }
  if (fd_ >= 0 && named_ && rows_on_disk_ == 0) {
    // The named file (no O_TMPFILE) holds no complete write yet: keep it header-free.
    if (::ftruncate(fd_, 0) != 0) {
      result.error = errno;
      result.operation = "ftruncate";
    }
    reset_buffer_to_header();
    return;
  }
  // Undo the partial write: the last row as it was, the size as it was.
  if (rewrite_) {
    std::size_t written = 0;
    (void)write_all(fd_, last_row_.data(), last_row_length_, last_row_start_, written);
  }
  if (::ftruncate(fd_, static_cast<off_t>(committed_)) != 0) {
    result.error = errno;
    result.operation = "ftruncate";
  }
  used_ = 0;
  buffer_start_ = committed_;
  buffer_has_row_ = false;
  rewrite_ = false;
  rows_buffered_ = 0;
}

RecordingFile::Result RecordingFile::write_out() noexcept {
  Result result = std::exchange(carry_, Result{});
  if (!open_ || rows_buffered_ == 0) return result;
  if (fd_ < 0) {
    const Result created = create_file();
    if (created.error != 0) {
      fail_write(result, created.error, created.operation);
      return result;
    }
  }
  std::size_t written = 0;
  const int error = write_all(fd_, buffer_.data(), used_, buffer_start_, written);
  if (error != 0) {
    fail_write(result, error, "write");
    return result;
  }
  dirty_ = true;
  if (!named_) {
    // The file now holds its header and whole rows: give it its name.
    const std::string self = "/proc/self/fd/" + std::to_string(fd_);
    if (::linkat(AT_FDCWD, self.c_str(), AT_FDCWD, path_.c_str(), AT_SYMLINK_FOLLOW) != 0) {
      fail_write(result, errno, "link");
      return result;
    }
    named_ = true;
  }
  result.bytes_written += used_;
  result.rows_written += rows_buffered_;
  rows_on_disk_ += rows_buffered_;
  committed_ = buffer_start_ + used_;
  keep_last_row(buffer_last_row_, used_ - buffer_last_row_);
  used_ = 0;
  buffer_start_ = committed_;
  buffer_has_row_ = false;
  rewrite_ = false;
  rows_buffered_ = 0;
  return result;
}

RecordingFile::Result RecordingFile::sync() noexcept {
  Result result;
  if (fd_ < 0 || !dirty_) return result;
  if (::fdatasync(fd_) != 0) {
    result.error = errno;
    result.operation = "fdatasync";
    return result;
  }
  dirty_ = false;
  result.synced = true;
  if (named_ && !dir_synced_) {
    // The name itself must survive a power cut too.
    const std::filesystem::path dir = path_.parent_path().empty() ? "." : path_.parent_path();
    const int dir_fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dir_fd >= 0) {
      if (::fsync(dir_fd) == 0) dir_synced_ = true;
      ::close(dir_fd);
    }
  }
  return result;
}

RecordingFile::Result RecordingFile::close() noexcept {
  Result result;
  if (!open_) return result;
  merge(result, write_out());
  merge(result, sync());
  // Rows still buffered here could not be written; they are lost with the file.
  result.rows_lost += rows_buffered_;
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  open_ = false;
  used_ = 0;
  rows_buffered_ = 0;
  return result;
}

}  // namespace selfsense::daemon
