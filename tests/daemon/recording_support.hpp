// Test helpers for the daemon tests: loop samples that look like a running loop, scratch
// directories, and reading back every recording file of a directory.
#pragma once

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "selfsense/io/recording.hpp"
#include "selfsense/runtime/loop_sample.hpp"

namespace selfsense::daemon::testing {

inline constexpr double kTs = 5e-5;  // 20 kHz

inline runtime::LoopSample make_sample(std::int64_t cycle) {
  const double t = static_cast<double>(cycle) * kTs;
  const double phase = 2.0 * M_PI * 3.0 * t;
  runtime::LoopSample s;
  s.cycle = cycle;
  s.t = t;
  s.e = 1.0e6 * (1.0 + std::sin(phase));
  s.d = 0.02 * (1.0 + std::sin(phase - 0.1));
  s.t_hat = -1.0e5 * std::cos(phase);
  s.s_hat = 5e-4 * (1.0 + std::sin(phase - 0.05));
  s.setpoint = 5e-4 * (1.0 + std::sin(phase));
  s.command = s.e;
  s.s_ref = s.s_hat * 1.001;
  s.t_ref = s.t_hat * 0.999;
  s.state = runtime::LoopState::kArmed;
  s.driver_status = static_cast<std::uint16_t>(cycle % 3);
  return s;
}

// A fresh directory under the system's temporary directory, removed at the end of the scope.
inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

inline void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::trunc);
  out << text;
  if (!out.flush()) throw std::runtime_error("cannot write " + path.string());
}

class ScratchDir final {
 public:
  explicit ScratchDir(const std::string& name)
      : path_(std::filesystem::temp_directory_path() /
              ("selfsense-" + name + "-" + std::to_string(::getpid()))) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code error;
    std::filesystem::remove_all(path_, error);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  ScratchDir(ScratchDir&&) = delete;
  ScratchDir& operator=(ScratchDir&&) = delete;
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// The *.csv files of dir whose name starts with prefix, in name order (= recording order).
inline std::vector<std::filesystem::path> csv_files(const std::filesystem::path& dir,
                                                    const std::string& prefix) {
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name.starts_with(prefix) && entry.path().extension() == ".csv") {
      files.push_back(entry.path());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

struct ReadBack {
  std::vector<std::filesystem::path> files;
  std::vector<double> cycle;  // every row of every file, in order
  std::vector<double> t;
  std::vector<double> e;
  std::vector<std::uintmax_t> sizes;
};

// Reads every file with the contract reader (which throws on anything malformed).
inline ReadBack read_back(const std::filesystem::path& dir, const std::string& prefix) {
  ReadBack out;
  out.files = csv_files(dir, prefix);
  for (const auto& file : out.files) {
    const io::Recording r = io::read_recording_csv(
        file, {{"t", "E", "D", "T_hat", "S_hat", "setpoint", "command", "state", "cycle"}});
    const auto cycle = r.column("cycle");
    const auto t = r.column("t");
    const auto e = r.column("E");
    out.cycle.insert(out.cycle.end(), cycle.begin(), cycle.end());
    out.t.insert(out.t.end(), t.begin(), t.end());
    out.e.insert(out.e.end(), e.begin(), e.end());
    out.sizes.push_back(std::filesystem::file_size(file));
  }
  return out;
}

}  // namespace selfsense::daemon::testing
