// `selfsense main-job-page DIR SEGMENT...`: the main job's HTML page (main_job_page.hpp) from
// what scripts/main_job.sh and scripts/main_job_report.sh leave in DIR: SEGMENT.path (the
// daemon's recording of each run), figures.txt (the report's line per run and the damping
// ratio) and faults.txt (the faulted runs, each naming the recording it spoiled). Writes
// DIR/main_job.html (or --out). A recording it cannot read is named on the page and on stderr,
// and the exit status is 1 once the page is written.
#include <CLI/CLI.hpp>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <memory>
#include <regex>
#include <string>
#include <vector>

#include "commands.hpp"
#include "selfsense/io/recording.hpp"
#include "selfsense/report/main_job_page.hpp"
#include "selfsense/runtime/supervisor.hpp"

namespace selfsense::cli {

using report::kStateFaulted;
using report::MainJobPage;
using report::MainJobRun;
using report::write_main_job_page;
namespace {

namespace fs = std::filesystem;

struct Options {
  fs::path dir{};
  std::vector<std::string> segments{};
  fs::path out{};
  std::string title{"selfsensed on the simulated transducer"};
};

// The file's lines; none when it does not exist.
std::vector<std::string> lines_of(const fs::path& path) {
  std::vector<std::string> lines;
  std::ifstream file(path);
  for (std::string line; std::getline(file, line);) {
    if (!line.empty()) lines.push_back(line);
  }
  return lines;
}

bool starts_with(const std::string& line, const std::string& prefix) {
  return line.compare(0, prefix.size(), prefix) == 0;
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

// The run's columns from its recording, or the reason there are none in run.error.
void read_run(MainJobRun& run, const fs::path& path, bool& failed) {
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
    (void)std::fprintf(stderr, "selfsense main-job-page: %s\n", e.what());
    failed = true;
  }
}

std::string path_of_segment(const fs::path& dir, const std::string& segment) {
  std::ifstream file(dir / (segment + ".path"));
  std::string path;
  std::getline(file, path);
  return path;
}

int run_command(const Options& o) {
  MainJobPage page;
  page.title = o.title;
  bool failed = false;
  const std::vector<std::string> figures = lines_of(o.dir / "figures.txt");
  for (const std::string& segment : o.segments) {
    MainJobRun run;
    run.heading = segment;
    run.kind = kind_of(segment);
    for (const std::string& line : figures) {
      if (starts_with(line, segment + ": ")) run.figures = line;  // the last one
    }
    const std::string path = path_of_segment(o.dir, segment);
    if (path.empty()) {
      run.error = "no recording: " + (o.dir / (segment + ".path")).string() + " names none";
      (void)std::fprintf(stderr, "selfsense main-job-page: %s\n", run.error.c_str());
      failed = true;
    } else {
      read_run(run, path, failed);
    }
    page.runs.push_back(std::move(run));
  }
  for (const std::string& line : figures) {
    if (starts_with(line, "damping: ") || starts_with(line, "self-heating: ")) {
      page.summary.push_back(line);
    }
  }
  // "FAULT: position: run 1 of 2: ...; recording: PATH" (scripts/daemon_runs.sh).
  const std::regex fault_line(
      R"(^FAULT: ([A-Za-z_-]+): (run [0-9]+ of [0-9]+): .*; recording: (.*)$)");
  page.fault_lines = lines_of(o.dir / "faults.txt");
  for (const std::string& line : page.fault_lines) {
    std::smatch m;
    if (!std::regex_match(line, m, fault_line) || !fs::is_regular_file(m[3].str())) continue;
    MainJobRun run;
    run.heading = m[1].str() + ", " + m[2].str() + " (faulted)";
    run.kind = kind_of(m[1].str());
    run.figures = line;
    read_run(run, m[3].str(), failed);
    page.faulted_runs.push_back(std::move(run));
  }
  const fs::path out = o.out.empty() ? o.dir / "main_job.html" : o.out;
  write_main_job_page(page, out);
  std::printf("wrote %s\n", out.string().c_str());
  return failed ? 1 : 0;
}

}  // namespace

void add_main_job_page_command(CLI::App& app) {
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "main-job-page",
      "Write the main job's HTML page from DIR (SEGMENT.path, figures.txt, faults.txt)");
  cmd->add_option("dir", o->dir, "The main job's output directory")->required();
  cmd->add_option("segments", o->segments, "Runs: position, force, undamped, damped")->required();
  cmd->add_option("--out", o->out, "The page (default DIR/main_job.html)");
  cmd->add_option("--title", o->title, "The page's heading");
  cmd->callback([o] {
    const int status = run_command(*o);
    if (status != 0) throw CommandExit{status};
  });
}

}  // namespace selfsense::cli
