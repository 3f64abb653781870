// Test helpers for the daemon tests: loop samples that look like a running loop and scratch
// directories (from tests/support), and reading back every recording file of a directory.
#pragma once

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "selfsense/io/recording.hpp"
#include "selfsense/runtime/loop_sample.hpp"
#include "support/loop_samples.hpp"
#include "support/scratch_dir.hpp"

namespace selfsense::daemon::testing {

inline constexpr double kTs = test::kSampleTime;  // 20 kHz

using test::read_text;
using test::ScratchDir;
using test::synthetic_sample;
using test::write_text;

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
