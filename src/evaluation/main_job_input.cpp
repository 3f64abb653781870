#include "selfsense/evaluation/main_job_input.hpp"

#include <cstddef>
#include <cstdint>
#include <exception>
#include <fstream>
#include <regex>
#include <utility>

#include "selfsense/io/recording.hpp"
#include "selfsense/runtime/supervisor.hpp"

namespace selfsense::evaluation {
namespace {

namespace fs = std::filesystem;
using report::kStateFaulted;
using report::MainJobRun;

// The file's lines; none when it does not exist.
std::vector<std::string> lines_of(const fs::path& path) {
  std::vector<std::string> lines;
  std::ifstream file(path);
  for (std::string line; std::getline(file, line);) {
    if (!line.empty()) lines.push_back(line);
  }
  return lines;
}

MainJobRun::Kind kind_of(const std::string& segment) {
  if (segment == "undamped" || segment == "damped") return MainJobRun::Kind::kRingDown;
  if (segment == "force") return MainJobRun::Kind::kForce;
  return MainJobRun::Kind::kPosition;
}

std::vector<double> column_or_empty(const io::Recording& r, const char* name) {
  if (!r.has(name)) return {};
  const std::span<const double> c = r.column(name);
  return {c.begin(), c.end()};
}

std::string fault_names(std::uint32_t bits) {
  std::string names;
  for (std::size_t i = 0; i < runtime::kFaultCount; ++i) {
    const auto f = static_cast<runtime::Fault>(i);
    if ((bits & runtime::bit(f)) == 0) continue;
    if (!names.empty()) names += ", ";
    names += runtime::to_string(f);
  }
  return names.empty() ? "none latched" : names;
}

// The run's columns from its recording, or the reason there are none in run.error (and in
// problems).
void read_run(MainJobRun& run, const fs::path& path, std::vector<std::string>& problems) {
  run.recording = path.string();
  try {
    const io::Recording r = io::read_recording_csv(path, io::ReadOptions{{"t", "state"}});
    const bool force = run.kind == MainJobRun::Kind::kForce;
    run.t = column_or_empty(r, "t");
    run.state = column_or_empty(r, "state");
    run.setpoint = column_or_empty(r, "setpoint");
    run.estimate = column_or_empty(r, force ? "T_hat" : "S_hat");
    run.reference = column_or_empty(r, force ? "T" : "S");
    run.field = column_or_empty(r, "E");
    run.mode = column_or_empty(r, "mode");
    run.temperature = column_or_empty(r, "temp");
    run.temperature_estimate = column_or_empty(r, "temp_equivalent");
    const std::vector<double> cycle = column_or_empty(r, "cycle");
    const std::vector<double> faults = column_or_empty(r, "faults");
    for (std::size_t i = 0; i < run.state.size(); ++i) {
      if (run.state[i] != kStateFaulted) continue;
      run.fault_t = run.t[i];
      run.fault_text =
          (i < faults.size() ? fault_names(static_cast<std::uint32_t>(faults[i]))
                             : std::string("a fault")) +
          (i < cycle.size() ? " at cycle " + std::to_string(static_cast<std::int64_t>(cycle[i]))
                            : std::string());
      break;
    }
  } catch (const std::exception& e) {
    run.error = std::string("no plot: ") + e.what();
    problems.emplace_back(e.what());
  }
}

std::string path_of_segment(const fs::path& dir, const std::string& segment) {
  std::ifstream file(dir / (segment + ".path"));
  std::string path;
  std::getline(file, path);
  return path;
}

}  // namespace

MainJobInput read_main_job(const fs::path& dir, std::span<const std::string> segments,
                           const std::string& title) {
  MainJobInput in;
  report::MainJobPage& page = in.page;
  page.title = title;
  const std::vector<std::string> figures = lines_of(dir / "figures.txt");
  for (const std::string& segment : segments) {
    MainJobRun run;
    run.heading = segment;
    run.kind = kind_of(segment);
    for (const std::string& line : figures) {
      if (line.starts_with(segment + ": ")) run.figures = line;  // the last one
    }
    const std::string path = path_of_segment(dir, segment);
    if (path.empty()) {
      run.error = "no recording: " + (dir / (segment + ".path")).string() + " names none";
      in.problems.push_back(run.error);
    } else {
      read_run(run, path, in.problems);
    }
    page.runs.push_back(std::move(run));
  }
  for (const std::string& line : figures) {
    if (line.starts_with("damping: ") || line.starts_with("self-heating: ")) {
      page.summary.push_back(line);
    }
  }
  // "FAULT: position: run 1 of 2: ...; recording: PATH" (scripts/daemon_runs.sh).
  const std::regex fault_line(
      R"(^FAULT: ([A-Za-z_-]+): (run [0-9]+ of [0-9]+): .*; recording: (.*)$)");
  page.fault_lines = lines_of(dir / "faults.txt");
  for (const std::string& line : page.fault_lines) {
    std::smatch m;
    if (!std::regex_match(line, m, fault_line) || !fs::is_regular_file(m[3].str())) continue;
    MainJobRun run;
    run.heading = m[1].str() + ", " + m[2].str() + " (faulted)";
    run.kind = kind_of(m[1].str());
    run.figures = line;
    read_run(run, m[3].str(), in.problems);
    page.faulted_runs.push_back(std::move(run));
  }
  return in;
}

}  // namespace selfsense::evaluation
