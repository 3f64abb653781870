// The main job's page (main_job_page.hpp): the samples the tracking error is drawn over, the
// ring-down window, and a page with its axes, legend, error panel and fault marks.
#include "selfsense/report/main_job_page.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace selfsense::report {
namespace {

std::size_t count(std::string_view text, std::string_view what) {
  std::size_t n = 0;
  for (std::size_t pos = text.find(what); pos != std::string_view::npos;
       pos = text.find(what, pos + what.size())) {
    ++n;
  }
  return n;
}

// A position run at 1 kHz: steps 0 -> 1e-3 at 1 s, armed throughout unless `fault_at` > 0.
MainJobRun position_run(double fault_at) {
  MainJobRun run;
  run.heading = "position";
  for (int i = 0; i < 2000; ++i) {
    const double t = 10.0 + 1e-3 * i;
    const double sp = t < 11.0 ? 2e-4 : 1e-3;
    run.t.push_back(t);
    run.setpoint.push_back(sp);
    run.estimate.push_back(sp + 1e-6);
    run.reference.push_back(sp + 2e-6);
    run.field.push_back(2e9 * sp);
    run.state.push_back(fault_at > 0.0 && t >= fault_at ? kStateFaulted : kStateArmed);
  }
  if (fault_at > 0.0) {
    run.fault_t = fault_at;
    run.fault_text = "overrun at cycle 115000";
  }
  return run;
}

TEST(MainJobPage, SettledSamplesFollowTheReportsRule) {
  const MainJobRun run = position_run(11.5);
  const std::vector<bool> settled = settled_samples(run.t, run.setpoint, run.state);
  ASSERT_EQ(settled.size(), run.t.size());
  EXPECT_FALSE(settled[0]);    // the first armed sample
  EXPECT_FALSE(settled[199]);  // 0.199 s after the start
  EXPECT_TRUE(settled[201]);   // (10.2 - 10.0 is just below 0.2 in double, as in awk)
  EXPECT_TRUE(settled[999]);
  EXPECT_FALSE(settled[1000]);  // the step at 11 s
  EXPECT_FALSE(settled[1199]);
  EXPECT_TRUE(settled[1201]);
  EXPECT_TRUE(settled[1499]);
  EXPECT_FALSE(settled[1500]);  // faulted from 11.5 s
  EXPECT_FALSE(settled[1999]);
}

TEST(MainJobPage, RingDownWindowStartsBeforeThePeak) {
  MainJobRun run;
  run.kind = MainJobRun::Kind::kRingDown;
  for (int i = 0; i < 700; ++i) {
    const double t = 1e-3 * i;
    const double s = t < 0.1 ? 0.0 : 5e-5 * std::exp(-(t - 0.1) / 0.02);
    run.t.push_back(t);
    run.estimate.push_back(6e-4 + s);
    run.reference.push_back(6e-4 + s);
    run.state.push_back(kStateArmed);
  }
  const RingDownWindow w = ring_down_window(run);
  ASSERT_TRUE(w.valid);
  EXPECT_NEAR(w.rest_reference, 6e-4, 1e-12);
  EXPECT_NEAR(w.t0, 0.05, 1e-9);
  EXPECT_NEAR(w.t1, 0.45, 1e-9);
  run.state.assign(run.state.size(), kStateFaulted);
  EXPECT_FALSE(ring_down_window(run).valid);
}

TEST(MainJobPage, RunsHaveAxesInUnitsTheErrorUnderneathAndFaultsMarked) {
  MainJobPage page;
  page.fault_lines.emplace_back("FAULT: position: run 1 of 2: overrun <late>; recording: x.csv");
  MainJobRun run = position_run(0.0);
  run.figures = "position: 2000 armed samples, setpoint range 0.0002 to 0.001 (strain): ...";
  page.runs.push_back(run);
  MainJobRun force = position_run(0.0);
  force.heading = "force";
  force.kind = MainJobRun::Kind::kForce;
  page.runs.push_back(force);
  MainJobRun faulted = position_run(11.5);
  faulted.heading = "position, run 1 of 2 (faulted)";
  page.faulted_runs.push_back(faulted);
  page.summary.emplace_back("damping: ring-down shortened 14.3x on true S");
  const std::string html = main_job_page_html(page);

  EXPECT_NE(html.find("Content-Security-Policy"), std::string::npos);
  // Two tracking runs and one faulted: a setpoint plot, an error plot and a field plot each.
  EXPECT_EQ(count(html, "<svg"), 9U);
  EXPECT_EQ(count(html, "</svg>"), 9U);
  EXPECT_EQ(count(html, ">time t [s]</text>"), 9U);
  EXPECT_EQ(count(html, ">strain S [1e-6]</text>"), 2U);
  EXPECT_EQ(count(html, ">stress T [MPa]</text>"), 1U);
  EXPECT_EQ(count(html, ">field E [kV/mm]</text>"), 3U);
  EXPECT_EQ(count(html, ">error [1e-6]</text>"), 2U);
  EXPECT_EQ(count(html, ">error [MPa]</text>"), 1U);
  EXPECT_NE(html.find(">position: tracking error</text>"), std::string::npos);
  EXPECT_NE(html.find(">S_hat (self-sensed)</text>"), std::string::npos);
  EXPECT_NE(html.find(">S (plant, true)</text>"), std::string::npos);
  EXPECT_NE(html.find(">setpoint</text>"), std::string::npos);
  // Strain in 1e-6: the 1e-3 step is at 1000; stress in MPa: 1e-3 Pa is 1e-9 MPa (axis in %g).
  EXPECT_NE(html.find(">1000</text>"), std::string::npos);
  // Only the faulted run has the fault marked: in each of its three plots.
  EXPECT_EQ(count(html, ">fault latched</text>"), 3U);
  EXPECT_EQ(count(html, ">faulted</text>"), 3U);
  EXPECT_NE(html.find("overrun at cycle 115000"), std::string::npos);
  EXPECT_NE(html.find("overrun &lt;late&gt;"), std::string::npos);
  EXPECT_NE(html.find("setpoint range 0.0002 to 0.001 (strain)"), std::string::npos);
  EXPECT_NE(html.find("damping: ring-down shortened 14.3x"), std::string::npos);
}

TEST(MainJobPage, RingDownRunsAndUnreadableRecordings) {
  MainJobPage page;
  MainJobRun run;
  run.heading = "damped";
  run.kind = MainJobRun::Kind::kRingDown;
  for (int i = 0; i < 700; ++i) {
    const double t = 1e-3 * i;
    run.t.push_back(t);
    run.estimate.push_back(6e-4 + (t < 0.1 ? 0.0 : 4e-5 * std::exp(-(t - 0.1) / 0.01)));
    run.reference.push_back(6e-4 + (t < 0.1 ? 0.0 : 5e-5 * std::exp(-(t - 0.1) / 0.01)));
    run.state.push_back(kStateArmed);
  }
  page.runs.push_back(run);
  MainJobRun missing;
  missing.heading = "undamped";
  missing.kind = MainJobRun::Kind::kRingDown;
  missing.error = "no plot: u.csv: cannot open";
  page.runs.push_back(missing);
  const std::string html = main_job_page_html(page);
  EXPECT_EQ(count(html, "<svg"), 2U);
  EXPECT_NE(html.find(">strain S - rest [1e-6]</text>"), std::string::npos);
  EXPECT_NE(html.find(">S_hat - S [1e-6]</text>"), std::string::npos);
  EXPECT_NE(html.find("no plot: u.csv: cannot open"), std::string::npos);
  EXPECT_EQ(html.find("nan"), std::string::npos);

  const std::filesystem::path path =
      std::filesystem::temp_directory_path() / "selfsense_main_job_page_test.html";
  write_main_job_page(page, path);
  std::ifstream file(path, std::ios::binary);
  const std::string written{std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
  std::filesystem::remove(path);
  EXPECT_EQ(written, html);
  EXPECT_THROW(write_main_job_page(page, "/nonexistent-dir/page.html"), std::runtime_error);
}

// The self-heating run (scripts/main_job.sh): open loop first, then position; with the plant's
// temperature and the adaptation's equivalent temperature recorded.
TEST(MainJobPage, TheSelfHeatingRunPlotsTheTemperaturesAndTheSelfSensingError) {
  MainJobRun adapted = position_run(0.0);
  adapted.heading = "heating-adapted";
  for (std::size_t i = 0; i < adapted.t.size(); ++i) {
    adapted.mode.push_back(adapted.t[i] < 11.0 ? 2.0 : 0.0);  // open-loop, then position
    adapted.temperature.push_back(25.0 + static_cast<double>(i) * 1e-2);
    adapted.temperature_estimate.push_back(25.0 + static_cast<double>(i) * 0.9e-2);
  }
  MainJobRun plain = adapted;
  plain.heading = "heating-plain";
  plain.temperature_estimate.clear();
  MainJobPage page;
  page.runs = {adapted, plain};
  const std::string html = main_job_page_html(page);
  // Each run: setpoint/estimate/truth, tracking error, S_hat - S, temperature, field.
  EXPECT_EQ(count(html, "<svg"), 10U);
  EXPECT_EQ(count(html, ">temperature [degC]</text>"), 2U);
  EXPECT_EQ(count(html, ">S_hat - S [1e-6]</text>"), 2U);
  EXPECT_EQ(count(html, ">plant (true)</text>"), 2U);
  EXPECT_EQ(count(html, ">equivalent (adaptation)</text>"), 1U);
  EXPECT_EQ(count(html, "this run does not adapt"), 1U);
  EXPECT_NE(html.find(">heating-adapted: the stack&#39;s temperature</text>"), std::string::npos)
      << html.substr(0, 2000);
  EXPECT_EQ(count(html, "in position mode (the gaps"), 2U);
  // A run without temperatures has no such plots.
  MainJobPage position_only;
  position_only.runs = {position_run(0.0)};
  const std::string other = main_job_page_html(position_only);
  EXPECT_EQ(count(other, "<svg"), 3U);
  EXPECT_EQ(count(other, "temperature"), 0U);
}

}  // namespace
}  // namespace selfsense::report
