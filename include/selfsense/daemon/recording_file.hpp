// One recording file as the writer thread fills it, kept so that whatever moment the process
// dies (kill -9), the file on disk is a valid contract recording that ends at a row boundary.
//
// How:
//  - The file gets its name only once it holds the header and at least one row: it is created
//    unnamed (O_TMPFILE) and linked to its name after its first write. A crash before that
//    leaves nothing; there is never an empty or header-only file. (On a file system without
//    O_TMPFILE the named file is created right before its first write.)
//  - Rows never straddle a 4096-byte boundary of the file. Linux stops a write(2) that is cut
//    short by a fatal signal, a full disk or a file-size limit only at a page boundary
//    (generic_perform_write copies one page at a time and checks for SIGKILL between pages), so
//    a cut write still ends at a row boundary. Where a row would cross the boundary, the row
//    before it is lengthened to end exactly there (RowFormat::pad: leading zeros in its cycle
//    cell); if that row is already on disk it is written again, lengthened, in the same write.
//  - A write that fails (disk full, I/O error) is undone: the file is truncated back to the last
//    complete write, and the rows of the failed write are reported as lost.
//  - sync() makes everything written durable (fdatasync, and the directory once after the name
//    appears), so a power cut keeps every row up to the last sync.
//
// Not thread-safe: one thread (the recorder's writer) uses it. Allocates only in the
// constructor and open(); add(), write_out(), sync() and close() are noexcept.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "selfsense/daemon/csv_row.hpp"
#include "selfsense/runtime/loop_sample.hpp"

namespace selfsense::daemon {

inline constexpr std::size_t kFilePageBytes = 4096;

class RecordingFile final {
 public:
  // What a write_out(), sync() or close() did. error is an errno value (0: none) and operation
  // names the system call that failed.
  struct Result {
    std::uint64_t rows_written{0};
    std::uint64_t rows_lost{0};
    std::uint64_t bytes_written{0};
    bool synced{false};
    int error{0};
    const char* operation{""};
  };

  // chunk_bytes: buffered rows are due for writing once they reach this size.
  RecordingFile(RowFormat format, std::size_t chunk_bytes);
  RecordingFile(const RecordingFile&) = delete;
  RecordingFile& operator=(const RecordingFile&) = delete;
  RecordingFile(RecordingFile&&) = delete;
  RecordingFile& operator=(RecordingFile&&) = delete;
  ~RecordingFile();

  // Starts a file that will be called `path` (which must not exist) once it has rows. A file
  // still open is closed first (its result is lost; close() it before to see it).
  void open(std::filesystem::path path, const std::vector<std::string>& comments);
  [[nodiscard]] bool is_open() const noexcept { return open_; }
  [[nodiscard]] const std::filesystem::path& path() const noexcept { return path_; }
  // True once the file exists under its name.
  [[nodiscard]] bool named() const noexcept { return named_; }

  // Adds a row; the caller has checked that sample.t is finite and > last_t() when has_rows().
  void add(const runtime::LoopSample& sample) noexcept;
  [[nodiscard]] bool has_rows() const noexcept { return rows_on_disk_ + rows_buffered_ > 0; }
  [[nodiscard]] double last_t() const noexcept { return last_t_; }
  [[nodiscard]] std::uint64_t rows() const noexcept { return rows_on_disk_ + rows_buffered_; }
  // The file's size once the buffered rows are written [bytes].
  [[nodiscard]] std::size_t bytes() const noexcept { return buffer_start_ + used_; }
  [[nodiscard]] bool write_due() const noexcept { return used_ >= chunk_bytes_; }

  // Writes the buffered rows with one pwrite(2) (looping over short writes).
  Result write_out() noexcept;
  // fdatasync (when anything was written since the last one).
  Result sync() noexcept;
  // write_out(), sync(), close(2). The file is complete; is_open() turns false.
  Result close() noexcept;

 private:
  Result create_file() noexcept;
  void fail_write(Result& result, int error, const char* operation) noexcept;
  void reset_buffer_to_header() noexcept;
  void keep_last_row(std::size_t start_in_buffer, std::size_t length) noexcept;

  RowFormat format_;
  std::size_t chunk_bytes_{0};
  std::vector<char> buffer_{};  // capacity fixed in the constructor
  std::size_t used_{0};
  std::size_t buffer_start_{0};  // file offset of buffer_[0]
  std::size_t committed_{0};     // file size on disk (a row boundary)
  std::size_t buffer_last_row_{0};
  bool buffer_has_row_{false};
  bool rewrite_{false};           // buffer_ starts with the file's last row again, lengthened
  std::vector<char> last_row_{};  // the last row on disk, as written
  std::size_t last_row_start_{0};
  std::size_t last_row_length_{0};
  std::string header_{};
  std::filesystem::path path_{};
  int fd_{-1};
  bool open_{false};
  bool named_{false};
  bool dirty_{false};       // written since the last fdatasync
  bool dir_synced_{false};  // the directory entry is durable
  std::uint64_t rows_on_disk_{0};
  std::uint64_t rows_buffered_{0};
  double last_t_{0.0};
  Result carry_{};  // of a write add() had to make, reported by the next write_out()
};

}  // namespace selfsense::daemon
