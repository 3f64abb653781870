#include "selfsense/daemon/prometheus.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <fstream>
#include <iterator>
#include <thread>

#include "daemon/recording_support.hpp"
#include "selfsense/daemon/recorder_metrics.hpp"

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

}  // namespace
}  // namespace selfsense::daemon
