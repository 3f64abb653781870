// The soak test with faults (issue 12, "Hardening"): selfsensed on the simulated transducer at
// 10 kHz, armed in position mode on a sine wave, while the plant's fault schedule injects every
// fault kind, the driver plays the setpoint watchdog, hostile clients use the control socket,
// SIGHUP reloads arrive and the recorder rotates its files. Then SIGTERM, and the recordings,
// the status figures, the resident memory and the timing evidence are checked
// (docs/reliability.md, "Soak test").
//
//   soak_driver --selfsensed PATH [--source DIR] [--seconds 75] [--rate 10000] [--work DIR]
//               [--keep]
// --rate 20000 is the recorder's 60 s at 20 kHz (docs/reliability.md): the loop at the plant's
// rate, every row recorded, none dropped.
// Exit 0 when every assertion holds, 1 with the failures listed, 2 on a usage error.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iostream>
#include <iterator>
#include <mutex>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "selfsense/daemon/control_client.hpp"
#include "soak/fault_plan.hpp"
#include "soak/recording_check.hpp"
#include "soak/scratch_config.hpp"
#include "soak/soak_figures.hpp"
#include "soak/socket_abuse.hpp"
#include "support/daemon_process.hpp"

namespace selfsense::soak {
namespace {

using Clock = std::chrono::steady_clock;
using nlohmann::json;
using test::DaemonProcess;

constexpr double kKp = 2.0e8;  // config/sim.yaml's position gain; reloads alternate with 0.9 kp
constexpr const char* kWave =
    R"({"request":"wave","shape":"sine","amplitude":3e-4,"offset":6e-4,"frequency_hz":1})";
constexpr const char* kStopWave = R"({"request":"wave","shape":"stop"})";

struct Options {
  std::filesystem::path selfsensed{};
  std::filesystem::path source{SELFSENSE_SOURCE_DIR};
  std::filesystem::path work{};
  double seconds{75.0};
  double rate_hz{10000.0};
  bool keep{false};
};

bool parse(int argc, char** argv, Options& o) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  for (std::size_t i = 0; i < args.size(); ++i) {
    const bool has_value = i + 1 < args.size();
    if (args[i] == "--selfsensed" && has_value) {
      o.selfsensed = args[++i];
    } else if (args[i] == "--source" && has_value) {
      o.source = args[++i];
    } else if (args[i] == "--work" && has_value) {
      o.work = args[++i];
    } else if (args[i] == "--seconds" && has_value) {
      o.seconds = std::stod(args[++i]);
    } else if (args[i] == "--rate" && has_value) {
      o.rate_hz = std::stod(args[++i]);
    } else if (args[i] == "--keep") {
      o.keep = true;
    } else {
      return false;
    }
  }
  // The plant runs at 20 kHz: the loop's rate must divide it.
  return !o.selfsensed.empty() && o.seconds >= 20.0 &&
         (o.rate_hz == 10000.0 || o.rate_hz == 20000.0);
}

std::filesystem::path make_work_dir() {
  std::string pattern = "/tmp/selfsense-soak-XXXXXX";
  if (::mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
  return pattern;
}

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1))
    ++n;
  return n;
}

// Resident memory sampled every 250 ms on its own thread.
class RssSampler final {
 public:
  explicit RssSampler(const DaemonProcess& daemon) : daemon_(&daemon) {
    thread_ = std::thread([this] { run(); });
  }
  RssSampler(const RssSampler&) = delete;
  RssSampler& operator=(const RssSampler&) = delete;
  RssSampler(RssSampler&&) = delete;
  RssSampler& operator=(RssSampler&&) = delete;
  ~RssSampler() { stop(); }
  void stop() {
    stop_.store(true);
    if (thread_.joinable()) thread_.join();
  }
  [[nodiscard]] std::vector<RssSample> samples() const {
    const std::lock_guard lock(mutex_);
    return samples_;
  }

 private:
  void run() {
    const Clock::time_point start = Clock::now();
    while (!stop_.load()) {
      if (const auto rss = daemon_->rss_bytes()) {
        const std::lock_guard lock(mutex_);
        samples_.push_back({std::chrono::duration<double>(Clock::now() - start).count(), *rss});
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(250));
    }
  }
  const DaemonProcess* daemon_;
  std::atomic<bool> stop_{false};
  mutable std::mutex mutex_{};
  std::vector<RssSample> samples_{};
  std::thread thread_{};
};

// The loop's driver: status polls, reset and re-arm after every fault, the planned watchdog
// items, reload requests. Runs on the main thread.
class LoopDriver final {
 public:
  LoopDriver(const Scratch& scratch, const std::vector<PlannedFault>& plan)
      : socket_(scratch.socket), plan_(plan), client_(socket_, std::chrono::seconds(5)) {}

  void run(double seconds, const std::function<void()>& every_poll) {
    const Clock::time_point start = Clock::now();
    Clock::time_point last_reload = start;
    while (Clock::now() - start < std::chrono::duration<double>(seconds)) {
      poll_once();
      every_poll();
      if (Clock::now() - last_reload > std::chrono::seconds(7)) {
        last_reload = Clock::now();
        const json r = request(R"({"request":"reload"})");
        ++figures_.reload_requests;
        if (!r.value("ok", false)) failures_.push_back("reload request refused: " + r.dump());
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }

  [[nodiscard]] json last_status() { return request(R"({"request":"status"})"); }
  [[nodiscard]] const std::vector<Poll>& polls() const { return polls_; }
  [[nodiscard]] const DriverFigures& figures() const { return figures_; }
  [[nodiscard]] const std::vector<std::string>& failures() const { return failures_; }

 private:
  json request(const std::string& line) {
    for (int attempt = 0; attempt < 2; ++attempt) {
      try {
        return json::parse(client_.exchange(line));
      } catch (const std::exception& e) {
        ++figures_.client_errors;
        failures_.push_back(std::string("the driver's connection: ") + e.what());
        client_ = daemon::ControlClient(socket_, std::chrono::seconds(5));
      }
    }
    return json::object();
  }

  void poll_once() {
    const Clock::time_point before = Clock::now();
    const json s = request(R"({"request":"status"})");
    const Clock::time_point after = Clock::now();
    if (!s.value("ok", false)) return;
    Poll p;
    p.wall_s = std::chrono::duration<double>(before.time_since_epoch()).count();
    p.rtt_s = std::chrono::duration<double>(after - before).count();
    p.cycles = s["counters"]["cycles"].get<std::int64_t>();
    p.missed_periods = s["timing"]["missed_periods"].get<std::int64_t>();
    p.overruns = s["timing"]["overruns"].get<std::int64_t>();
    polls_.push_back(p);
    const std::string state = s["state"].get<std::string>();
    if (state == "faulted") {
      if (request(R"({"request":"reset"})").value("ok", false)) {
        ++figures_.resets;
        arm();
      }
    } else if (state == "ready") {
      arm();
    } else if (state == "armed") {
      play_watchdog(p.cycles);
    }
  }

  // The wave first, then arm: the watchdog never sees an armed loop without a wave.
  void arm() {
    if (!request(kWave).value("ok", false)) return;
    if (request(R"({"request":"arm"})").value("ok", false)) ++figures_.arms;
  }

  void play_watchdog(std::int64_t cycles) {
    for (; next_watchdog_ < plan_.size(); ++next_watchdog_) {
      if (plan_[next_watchdog_].source == Source::kWatchdog) break;
    }
    if (next_watchdog_ == plan_.size() || cycles < plan_[next_watchdog_].start_cycle) return;
    if (request(kStopWave).value("ok", false)) ++figures_.waves_stopped;
    ++next_watchdog_;
  }

  std::filesystem::path socket_;
  const std::vector<PlannedFault>& plan_;
  daemon::ControlClient client_;
  std::size_t next_watchdog_{0};
  std::vector<Poll> polls_{};
  DriverFigures figures_{};
  std::vector<std::string> failures_{};
};

int run(const Options& o) {
  const std::filesystem::path work = o.work.empty() ? make_work_dir() : o.work;
  std::filesystem::create_directories(work);
  PlanSettings settings;
  settings.seconds = o.seconds;
  settings.rate_hz = o.rate_hz;
  const std::vector<PlannedFault> plan = make_plan(settings);
  const Scratch scratch = write_scratch(o.source, work, plant_faults_yaml(plan, settings.rate_hz),
                                        kKp, settings.rate_hz);
  std::printf("soak: %g s at %g Hz, %zu planned items, work directory %s\n", o.seconds, o.rate_hz,
              plan.size(), work.c_str());
  static_cast<void>(std::fflush(stdout));

  Report report;
  report.seconds = o.seconds;
  report.rate_hz = o.rate_hz;
  report.plan = plan;
  DaemonProcess daemon(o.selfsensed, scratch.config, work / "selfsensed");
  for (int i = 0; i < 200 && !std::filesystem::exists(scratch.socket); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  if (!std::filesystem::exists(scratch.socket)) {
    static_cast<void>(std::fprintf(stderr, "soak: no control socket; daemon log:\n%s\n",
                                   read_text(work / "selfsensed.err").c_str()));
    return 1;
  }
  RssSampler rss(daemon);
  // The driver takes its slot before the abuse starts: a connection made while the abuse holds
  // every slot is refused by design (max_clients), which is the abuse's test, not the driver's.
  LoopDriver driver(scratch, plan);
  static_cast<void>(driver.last_status());
  SocketAbuse abuse(scratch.socket, scratch.max_clients, 2, 12345U);
  const Clock::time_point start = Clock::now();
  Clock::time_point last_hup = start;
  driver.run(o.seconds, [&] {
    if (Clock::now() - last_hup < std::chrono::seconds(3)) return;
    last_hup = Clock::now();
    ++report.sighups;
    write_daemon_config(o.source, scratch, report.sighups % 2 == 1 ? 0.9 * kKp : kKp);
    daemon.signal(SIGHUP);
  });
  abuse.stop();
  rss.stop();
  report.final_status = driver.last_status();
  report.abuse = abuse.counts();
  report.polls = driver.polls();
  report.driver = driver.figures();
  report.driver_failures = driver.failures();
  report.rss = rss.samples();
  report.wall_s = std::chrono::duration<double>(Clock::now() - start).count();

  daemon.signal(SIGTERM);
  const std::optional<int> status = daemon.wait(std::chrono::seconds(30));
  report.exit_status = status.value_or(-1);
  const std::string out = read_text(work / "selfsensed.out");
  const std::string err = read_text(work / "selfsensed.err");
  const std::size_t at = out.find("stopped at cycle ");
  report.stopped_cycle = at == std::string::npos ? 0 : std::stoll(out.substr(at + 17));
  report.reloads_logged = count_of(err, "reloaded gains, filters, limits");
  report.reloads_refused = count_of(err, "reload refused");

  RecordingExpectations expect;
  expect.rate_hz = scratch.rate_hz;
  expect.watchdog_s = scratch.watchdog_s;
  expect.last_cycle = report.stopped_cycle;
  expect.overruns_shown = report.final_status["timing"].value("overruns", 0) > 0;
  report.recordings = check_recordings(scratch.recordings, plan, expect);

  const bool ok = judge(report);
  print_report(report, std::cout);
  if (!o.keep) std::filesystem::remove_all(work);
  return ok ? 0 : 1;
}

}  // namespace
}  // namespace selfsense::soak

int main(int argc, char** argv) {
  selfsense::soak::Options options;
  if (!selfsense::soak::parse(argc, argv, options)) {
    static_cast<void>(
        std::fprintf(stderr,
                     "usage: soak_driver --selfsensed PATH [--source DIR] [--seconds S>=20] "
                     "[--rate 10000|20000] [--work DIR] [--keep]\n"));
    return 2;
  }
  try {
    return selfsense::soak::run(options);
  } catch (const std::exception& e) {
    static_cast<void>(std::fprintf(stderr, "soak: %s\n", e.what()));
    return 1;
  }
}
