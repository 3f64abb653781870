// `selfsense main-job-page DIR SEGMENT...`: the main job's HTML page (main_job_page.hpp) from
// what scripts/main_job.sh and scripts/main_job_report.sh leave in DIR: SEGMENT.path (the
// daemon's recording of each run), figures.txt (the report's line per run and the damping
// ratio) and faults.txt (the faulted runs, each naming the recording it spoiled). Writes
// DIR/main_job.html (or --out). A recording it cannot read is named on the page and on stderr,
// and the exit status is 1 once the page is written.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "selfsense/evaluation/main_job_input.hpp"
#include "selfsense/report/main_job_page.hpp"

namespace selfsense::cli {
namespace {

namespace fs = std::filesystem;

struct Options {
  fs::path dir{};
  std::vector<std::string> segments{};
  fs::path out{};
  std::string title{"selfsensed on the simulated transducer"};
};

int run_command(const Options& o) {
  const evaluation::MainJobInput in = evaluation::read_main_job(o.dir, o.segments, o.title);
  for (const std::string& problem : in.problems)
    (void)std::fprintf(stderr, "selfsense main-job-page: %s\n", problem.c_str());
  const fs::path out = o.out.empty() ? o.dir / "main_job.html" : o.out;
  report::write_main_job_page(in.page, out);
  std::printf("wrote %s\n", out.string().c_str());
  return in.problems.empty() ? 0 : 1;
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
