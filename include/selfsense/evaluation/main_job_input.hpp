// The main job's page input (report/main_job_page.hpp) from what scripts/main_job.sh and
// scripts/main_job_report.sh leave in a directory (`selfsense main-job-page`): SEGMENT.path (the
// daemon's recording of each run), figures.txt (the report's line per run and the damping ratio)
// and faults.txt (the faulted runs, each naming the recording it spoiled).
#pragma once

#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "selfsense/report/main_job_page.hpp"

namespace selfsense::evaluation {

struct MainJobInput {
  report::MainJobPage page{};
  // What could not be read, in the order it was met (a segment naming no recording, a recording
  // that is not one); each such run is on the page with its error instead of plots.
  std::vector<std::string> problems{};
};

// The page for the runs SEGMENTS (position, force, undamped, damped) of DIR: each with its
// figures line and its recording's columns, the summary lines, and the faulted runs whose
// recordings exist.
[[nodiscard]] MainJobInput read_main_job(const std::filesystem::path& dir,
                                         std::span<const std::string> segments,
                                         const std::string& title);

}  // namespace selfsense::evaluation
