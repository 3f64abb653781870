#include "selfsense/daemon/prometheus.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <fstream>
#include <iterator>
#include <thread>

#include "daemon/exposition_check.hpp"
#include "daemon/recording_support.hpp"
#include "selfsense/daemon/recorder_metrics.hpp"
#include "selfsense/daemon/telemetry_metrics.hpp"
#include "selfsense/runtime/supervisor.hpp"

namespace selfsense::daemon {
namespace {

TEST(Prometheus, ExpositionTextIsExact) {
  const std::vector<MetricFamily> families{
      {"selfsense_loop_cycles_total",
       "Loop cycles run.",
       MetricType::kCounter,
       {{{{"board", "b1"}}, 1200000.0}}},
      {"selfsense_latency_seconds",
       "Wake-up latency\\quantiles\nby q.",
       MetricType::kGauge,
       {{{{"q", "0.99"}, {"note", "a \"quoted\" \\ path\nnext"}}, 1.25e-5},
        {{}, std::numeric_limits<double>::infinity()},
        {{{"q", "nan"}}, std::nan("")},
        {{{"q", "neg"}}, -3.0}}},
  };
  EXPECT_EQ(format_exposition(families),
            "# HELP selfsense_loop_cycles_total Loop cycles run.\n"
            "# TYPE selfsense_loop_cycles_total counter\n"
            "selfsense_loop_cycles_total{board=\"b1\"} 1200000\n"
            "# HELP selfsense_latency_seconds Wake-up latency\\\\quantiles\\nby q.\n"
            "# TYPE selfsense_latency_seconds gauge\n"
            "selfsense_latency_seconds{q=\"0.99\",note=\"a \\\"quoted\\\" \\\\ path\\nnext\"} "
            "1.25e-05\n"
            "selfsense_latency_seconds +Inf\n"
            "selfsense_latency_seconds{q=\"nan\"} NaN\n"
            "selfsense_latency_seconds{q=\"neg\"} -3\n");
}

TEST(Prometheus, BadNamesAreRefusedByName) {
  EXPECT_TRUE(valid_metric_name("a:b_c9"));
  EXPECT_FALSE(valid_metric_name("9a"));
  EXPECT_FALSE(valid_metric_name("a-b"));
  EXPECT_FALSE(valid_metric_name(""));
  EXPECT_TRUE(valid_label_name("_x1"));
  EXPECT_FALSE(valid_label_name("__reserved"));
  EXPECT_FALSE(valid_label_name("a:b"));
  const auto message = [](const std::vector<MetricFamily>& f) {
    try {
      (void)format_exposition(f);
    } catch (const MetricError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message({{"bad-name", "", MetricType::kGauge, {}}}),
            "metric name 'bad-name' is not [a-zA-Z_:][a-zA-Z0-9_:]*");
  EXPECT_EQ(message({{"m", "", MetricType::kGauge, {{{{"__x", "v"}}, 1.0}}}}),
            "metric 'm': label name '__x' is not [a-zA-Z_][a-zA-Z0-9_]* or starts with __");
  EXPECT_EQ(message({{"m", "", MetricType::kGauge, {}}, {"m", "", MetricType::kGauge, {}}}),
            "metric 'm' given twice");
}

std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A reader polling the file while it is rewritten sees one whole version or the other.
TEST(Prometheus, TextfileIsReplacedAtomically) {
  const testing::ScratchDir dir("prom");
  const auto path = dir.path() / "selfsense.prom";
  const std::string a(200000, 'a');
  const std::string b(150000, 'b');
  write_textfile(path, a);
  std::atomic<bool> done{false};
  std::thread writer([&] {
    for (int i = 0; i < 200; ++i)
      write_textfile(path, i % 2 == 0 ? b : a);
    done.store(true);
  });
  int reads = 0;
  int torn = 0;
  while (!done.load()) {
    const std::string text = slurp(path);
    if (text != a && text != b) ++torn;
    ++reads;
  }
  writer.join();
  EXPECT_EQ(torn, 0) << "of " << reads << " reads";
  EXPECT_GT(reads, 0);
  EXPECT_EQ(testing::csv_files(dir.path(), "").size(), 0U);
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()),
                          std::filesystem::directory_iterator()),
            1);  // no temporary left behind
  EXPECT_THROW(write_textfile(dir.path() / "no" / "x.prom", a), std::runtime_error);
}

TEST(Prometheus, RecorderCountersBecomeValidMetrics) {
  RecorderCounters c;
  c.rows_written = 42;
  c.recording = true;
  const std::string text = format_exposition(recorder_metrics(c, {{"board", "b1"}}));
  EXPECT_NE(text.find("selfsense_recorder_rows_written_total{board=\"b1\"} 42\n"),
            std::string::npos);
  EXPECT_NE(text.find("# TYPE selfsense_recorder_recording gauge\n"
                      "selfsense_recorder_recording{board=\"b1\"} 1\n"),
            std::string::npos);
}

std::string joined(const std::vector<std::string>& lines) {
  std::string out;
  for (const std::string& l : lines)
    out += l + "\n";
  return out;
}

// The checker itself finds each kind of mistake (else the test below could pass on bad text).
TEST(Prometheus, TheExpositionCheckerFindsMistakes) {
  const auto problems = [](const std::string& text) {
    return test::check_exposition(text).problems.size();
  };
  const std::string good =
      "# HELP a_total A.\n# TYPE a_total counter\na_total{x=\"1\"} 2\na_total{x=\"2\"} 3\n";
  EXPECT_EQ(problems(good), 0U) << joined(test::check_exposition(good).problems);
  EXPECT_EQ(problems("a_total 1\n"), 1U);                                    // no HELP/TYPE
  EXPECT_EQ(problems("# HELP b B.\n# TYPE b gauge\nb one\n"), 1U);           // not a number
  EXPECT_EQ(problems("# HELP b-c B.\n"), 1U);                                // bad name
  EXPECT_EQ(problems("# HELP b B.\n# TYPE b counter\nb 1\n"), 1U);           // counter not _total
  EXPECT_EQ(problems("# HELP b B.\n# TYPE b gauge\nb{__x=\"1\"} 1\n"), 1U);  // reserved label
  EXPECT_EQ(problems(good + "# HELP c C.\n# TYPE c gauge\nc 1\na_total{x=\"3\"} 1\n"),
            1U);                                                       // two blocks
  EXPECT_EQ(problems("# HELP b B.\n# TYPE b gauge\nb 1\nb 2\n"), 1U);  // same labels twice
  EXPECT_EQ(problems("# HELP b B.\n# TYPE b gauge\nb 1"), 1U);         // no final line feed
}

// Every family the daemon's telemetry file holds, formatted: valid exposition text, and the
// driver's counters, fault counts and recorder counters in it under their names.
TEST(Prometheus, TelemetryFamiliesAreValidExposition) {
  runtime::StatusSnapshot s;
  s.cycle = 123456;
  s.state = runtime::LoopState::kArmed;
  s.fault_records[static_cast<std::size_t>(runtime::Fault::kDriverError)].count = 4;
  s.wake_latency_p99_ns = 25'000;
  s.driver.reads = 1000;
  s.driver.crc_errors = 7;
  s.driver.add_event("no_new_data", 3);
  s.driver.add_event("reinits", 1);
  s.driver.add_event("no_new_data", 9);  // a repeated name is left out, not a second series
  s.driver.add_event(nullptr, 5);        // so is a missing one
  RecorderCounters rec;
  rec.rows_written = 42;
  rec.samples_dropped = 2;
  std::vector<MetricFamily> families = loop_metrics(s);
  for (MetricFamily& f : driver_metrics("spi", s.driver))
    families.push_back(std::move(f));
  for (MetricFamily& f : recorder_metrics(rec))
    families.push_back(std::move(f));
  const std::string text = format_exposition(families);
  const test::Exposition x = test::check_exposition(text);
  EXPECT_TRUE(x.problems.empty()) << joined(x.problems) << text;
  const auto value = [&](const std::string& name, const std::string& labels) {
    const auto f = x.samples.find(name);
    if (f == x.samples.end()) return -1.0;
    const auto v = f->second.find(labels);
    return v == f->second.end() ? -1.0 : v->second;
  };
  EXPECT_EQ(value("selfsense_driver_crc_errors_total", "driver=spi;"), 7.0);
  EXPECT_EQ(value("selfsense_driver_reads_total", "driver=spi;"), 1000.0);
  EXPECT_EQ(value("selfsense_driver_events_total", "driver=spi;event=no_new_data;"), 3.0);
  EXPECT_EQ(value("selfsense_driver_events_total", "driver=spi;event=reinits;"), 1.0);
  EXPECT_EQ(x.samples.at("selfsense_driver_events_total").size(), 2U);
  EXPECT_EQ(value("selfsense_loop_faults_total", "fault=driver_error;"), 4.0);
  EXPECT_EQ(value("selfsense_loop_faults_total", "fault=watchdog;"), 0.0);
  EXPECT_EQ(x.samples.at("selfsense_loop_faults_total").size(), runtime::kFaultCount);
  EXPECT_EQ(value("selfsense_loop_cycles", ""), 123456.0);
  EXPECT_EQ(value("selfsense_loop_state", ""), 2.0);
  EXPECT_DOUBLE_EQ(value("selfsense_loop_wake_latency_p99_seconds", ""), 25e-6);
  EXPECT_EQ(value("selfsense_recorder_rows_written_total", ""), 42.0);
  EXPECT_EQ(value("selfsense_recorder_samples_dropped_total", ""), 2.0);
  EXPECT_EQ(x.types.at("selfsense_driver_events_total"), "counter");
  EXPECT_EQ(x.types.at("selfsense_loop_faults_total"), "counter");
  EXPECT_EQ(x.types.at("selfsense_loop_cycles"), "gauge");
  // No temperature measured (the sample's is NaN): no series, rather than a NaN.
  EXPECT_EQ(x.samples.count("selfsense_stack_temperature_celsius"), 0U);
  s.last.temp_ref = 41.25;
  const test::Exposition warm = test::check_exposition(format_exposition(loop_metrics(s)));
  EXPECT_TRUE(warm.problems.empty()) << joined(warm.problems);
  EXPECT_EQ(warm.samples.at("selfsense_stack_temperature_celsius").at(""), 41.25);
  EXPECT_EQ(warm.types.at("selfsense_stack_temperature_celsius"), "gauge");
}

}  // namespace
}  // namespace selfsense::daemon
