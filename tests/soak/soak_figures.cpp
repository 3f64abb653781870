#include "soak/soak_figures.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>

#include "support/sanitizers.hpp"

namespace selfsense::soak {
namespace {

constexpr double kMib = 1024.0 * 1024.0;

// AddressSanitizer keeps freed memory in its quarantine (up to 256 MiB) before reusing it, so the
// daemon's resident memory grows under it by design: measured there, asserted in other builds.
using test::kAddressSanitizer;

std::uint64_t counter(const nlohmann::json& status, const char* name) {
  const auto& c = status.value("counters", nlohmann::json::object());
  return c.contains(name) && c[name].is_number_unsigned() ? c[name].get<std::uint64_t>() : ~0ULL;
}

void judge_timing(Report& r) {
  if (r.polls.size() < 2) {
    r.failures.emplace_back("fewer than two status polls");
    return;
  }
  // Deadlines the wall clock says passed, against cycles run plus periods the statistics
  // count as missed. The published counts lag: cycles by up to a status period (100), the
  // timing by up to two publications (2000 cycles); the poll's own time is uncertain by its
  // round trip.
  const auto check = [&r](const Poll& a, const Poll& b) {
    const double expected = (b.wall_s - a.wall_s) * r.rate_hz;
    const auto seen =
        static_cast<double>((b.cycles - a.cycles) + (b.missed_periods - a.missed_periods));
    const double tolerance = 2100.0 + r.rate_hz * (a.rtt_s + b.rtt_s) + 1e-4 * expected;
    r.timing_worst_gap_cycles = std::max(r.timing_worst_gap_cycles, expected - seen);
    if (std::abs(expected - seen) > tolerance) {
      r.failures.push_back("timing: " + std::to_string(expected) + " deadlines passed from " +
                           std::to_string(a.wall_s) + " s, the loop ran or counted " +
                           std::to_string(seen) + " (tolerance " + std::to_string(tolerance) + ")");
    }
  };
  std::size_t a = 0;
  for (std::size_t b = 1; b < r.polls.size(); ++b) {
    if (r.polls[b].wall_s - r.polls[a].wall_s < kTimingWindowS) continue;
    check(r.polls[a], r.polls[b]);
    a = b;
  }
  const Poll& first = r.polls.front();
  const Poll& last = r.polls.back();
  check(first, last);
  r.deadlines = std::llround((last.wall_s - first.wall_s) * r.rate_hz);
  r.cycles_run = last.cycles - first.cycles;
  r.missed_counted = last.missed_periods - first.missed_periods;
  std::vector<double> rtt;
  for (const Poll& p : r.polls)
    rtt.push_back(p.rtt_s);
  std::sort(rtt.begin(), rtt.end());
  r.poll_rtt_max_s = rtt.back();
  r.poll_rtt_p99_s = rtt[static_cast<std::size_t>(0.99 * static_cast<double>(rtt.size() - 1))];
  if (r.poll_rtt_max_s > kPollRttMaxS) {
    r.failures.push_back("a status poll took " + std::to_string(r.poll_rtt_max_s) + " s");
  }
}

void judge_rss(Report& r) {
  if (r.rss.size() < 20) {
    r.failures.emplace_back("fewer than 20 memory samples");
    return;
  }
  const double end = r.rss.back().t_s;
  double baseline = 0.0;
  double final = 0.0;
  double sx = 0.0;
  double sy = 0.0;
  double sxx = 0.0;
  double sxy = 0.0;
  double n = 0.0;
  for (const RssSample& s : r.rss) {
    const double mib = static_cast<double>(s.bytes) / kMib;
    if (s.t_s >= 0.2 * end && s.t_s < 0.45 * end) baseline = std::max(baseline, mib);
    if (s.t_s >= 0.75 * end) final = std::max(final, mib);
    if (s.t_s >= 0.2 * end) {
      sx += s.t_s;
      sy += mib;
      sxx += s.t_s * s.t_s;
      sxy += s.t_s * mib;
      n += 1.0;
    }
  }
  r.rss_baseline_mib = baseline;
  r.rss_final_mib = final;
  r.rss_slope_kib_per_min = (n * sxy - sx * sy) / (n * sxx - sx * sx) * 1024.0 * 60.0;
  if (final > baseline + kRssGrowthMaxMib && !kAddressSanitizer) {
    r.failures.push_back("resident memory grew from " + std::to_string(baseline) + " MiB to " +
                         std::to_string(final) + " MiB");
  }
}

void judge_abuse(Report& r) {
  const AbuseCounts& a = r.abuse;
  for (const std::string& f : a.failures)
    r.failures.push_back("socket: " + f);
  const std::map<std::string, std::uint64_t> each{
      {"garbage lines", a.garbage_lines},         {"cut lines", a.cut_lines},
      {"oversize lines", a.oversize_lines},       {"flood replies", a.flood_replies},
      {"unread floods", a.unread_floods},         {"churn connections", a.churn_connections},
      {"max_clients rounds", a.max_client_rounds}};
  for (const auto& [what, n] : each) {
    if (n == 0) r.failures.push_back("socket: no " + what + " in the run");
  }
}

void judge_daemon(Report& r) {
  if (r.exit_status != 0) {
    r.failures.push_back("selfsensed exited with " + std::to_string(r.exit_status) +
                         " after SIGTERM");
  }
  for (const std::string& f : r.driver_failures)
    r.failures.push_back("driver: " + f);
  if (r.reloads_logged != r.sighups || r.reloads_refused != 0) {
    r.failures.push_back(std::to_string(r.sighups) + " SIGHUPs, " +
                         std::to_string(r.reloads_logged) + " reloads logged, " +
                         std::to_string(r.reloads_refused) + " refused");
  }
  const nlohmann::json& s = r.final_status;
  for (const char* zero : {"samples_dropped", "rows_lost", "write_errors"}) {
    if (counter(s, zero) != 0) {
      r.failures.push_back(std::string("status counters.") + zero + " = " +
                           std::to_string(counter(s, zero)));
    }
  }
  if (counter(s, "files") < 2 || counter(s, "files") == ~0ULL) {
    r.failures.emplace_back("the recorder did not rotate (counters.files < 2)");
  }
  if (r.recordings.files != counter(s, "files")) {
    r.failures.push_back("status says " + std::to_string(counter(s, "files")) + " files, " +
                         std::to_string(r.recordings.files) + " found");
  }
}

void judge_coverage(Report& r) {
  std::map<std::string, int> planned;
  std::map<std::string, int> seen;
  for (const PlannedFault& p : r.plan)
    ++planned[p.name];
  for (const EpisodeFigures& e : r.recordings.episodes)
    ++seen[e.name];
  for (const auto& [name, n] : planned) {
    if (seen[name] != n) {
      r.failures.push_back(name + ": " + std::to_string(n) + " planned, " +
                           std::to_string(seen[name]) + " checked");
    }
  }
}

}  // namespace

bool judge(Report& r) {
  r.failures.clear();
  judge_daemon(r);
  judge_timing(r);
  judge_rss(r);
  judge_abuse(r);
  for (const std::string& f : r.recordings.failures)
    r.failures.push_back("recording: " + f);
  judge_coverage(r);
  return r.failures.empty();
}

void print_report(const Report& r, std::ostream& out) {
  const auto line = [&out](const char* format, auto... args) {
    std::array<char, 512> text{};
    static_cast<void>(std::snprintf(text.data(), text.size(), format, args...));
    out << text.data() << '\n';
  };
  const nlohmann::json& s = r.final_status;
  line("soak: %.0f s requested, %.1f s driven; selfsensed exit %d, stopped at cycle %lld",
       r.seconds, r.wall_s, r.exit_status, static_cast<long long>(r.stopped_cycle));
  line(
      "recordings: %zu files, %lld rows, cycles %lld..%lld, %lld missing; status: dropped %llu, "
      "rows_lost %llu, write_errors %llu, flight_dumps %llu",
      r.recordings.files, static_cast<long long>(r.recordings.rows),
      static_cast<long long>(r.recordings.first_cycle),
      static_cast<long long>(r.recordings.last_cycle),
      static_cast<long long>(r.recordings.missing_cycles),
      static_cast<unsigned long long>(counter(s, "samples_dropped")),
      static_cast<unsigned long long>(counter(s, "rows_lost")),
      static_cast<unsigned long long>(counter(s, "write_errors")),
      static_cast<unsigned long long>(counter(s, "flight_dumps")));
  // Per kind: how many, armed when hit, cycles latched, time to armed again, tracking after.
  struct Kind {
    int n{0};
    int armed{0};
    std::int64_t latched_max{0};
    std::int64_t rearm_max{0};
    double rms_max{0.0};
  };
  std::map<std::string, Kind> kinds;
  for (const EpisodeFigures& e : r.recordings.episodes) {
    Kind& k = kinds[e.name];
    ++k.n;
    k.armed += e.armed_before ? 1 : 0;
    k.latched_max = std::max(k.latched_max, e.latched_cycles);
    k.rearm_max = std::max(k.rearm_max, e.rearm_cycles);
    k.rms_max = std::max(k.rms_max, e.tracking_rms);
  }
  line("%-36s %4s %6s %12s %12s %14s", "item", "n", "armed", "latched max", "re-armed max",
       "track RMS max");
  for (const auto& [name, k] : kinds) {
    line("%-36s %4d %6d %10.1f ms %10.1f ms %14.3g", name.c_str(), k.n, k.armed,
         static_cast<double>(k.latched_max) / r.rate_hz * 1e3,
         static_cast<double>(k.rearm_max) / r.rate_hz * 1e3, k.rms_max);
  }
  line(
      "driver: %llu resets, %llu arms, %llu waves stopped (watchdog), %llu reload requests, "
      "%llu SIGHUPs (%zu logged), poll round trip p99 %.1f ms max %.1f ms",
      static_cast<unsigned long long>(r.driver.resets),
      static_cast<unsigned long long>(r.driver.arms),
      static_cast<unsigned long long>(r.driver.waves_stopped),
      static_cast<unsigned long long>(r.driver.reload_requests),
      static_cast<unsigned long long>(r.sighups), r.reloads_logged, r.poll_rtt_p99_s * 1e3,
      r.poll_rtt_max_s * 1e3);
  const AbuseCounts& a = r.abuse;
  line(
      "socket: %llu garbage lines, %llu cut lines, %llu oversize, %llu flood replies, %llu "
      "unread floods, %llu churn, %llu max_clients rounds, %llu refused while busy",
      static_cast<unsigned long long>(a.garbage_lines),
      static_cast<unsigned long long>(a.cut_lines),
      static_cast<unsigned long long>(a.oversize_lines),
      static_cast<unsigned long long>(a.flood_replies),
      static_cast<unsigned long long>(a.unread_floods),
      static_cast<unsigned long long>(a.churn_connections),
      static_cast<unsigned long long>(a.max_client_rounds),
      static_cast<unsigned long long>(a.refused_busy));
  const nlohmann::json timing = s.value("timing", nlohmann::json::object());
  line(
      "timing: %lld deadlines (wall clock), %lld cycles run, %lld missed counted; worst "
      "uncounted gap %.0f cycles; overruns %lld, overrun faults %lld; wake p99 %lld ns max %lld "
      "ns; cycle p99 %lld ns max %lld ns",
      static_cast<long long>(r.deadlines), static_cast<long long>(r.cycles_run),
      static_cast<long long>(r.missed_counted), r.timing_worst_gap_cycles,
      static_cast<long long>(timing.value("overruns", -1LL)),
      static_cast<long long>(r.recordings.overrun_faults),
      static_cast<long long>(timing["wake_latency_ns"].value("p99", -1LL)),
      static_cast<long long>(timing["wake_latency_ns"].value("max", -1LL)),
      static_cast<long long>(timing["cycle_time_ns"].value("p99", -1LL)),
      static_cast<long long>(timing["cycle_time_ns"].value("max", -1LL)));
  line(
      "memory: RSS %.1f MiB (20-45 %% of the run, max) -> %.1f MiB (last quarter, max), "
      "slope %.1f KiB/min after 20 %%%s",
      r.rss_baseline_mib, r.rss_final_mib, r.rss_slope_kib_per_min,
      kAddressSanitizer ? " (not asserted: AddressSanitizer's quarantine)" : "");
  for (const std::string& f : r.failures)
    out << "FAIL: " << f << '\n';
  out << (r.failures.empty() ? "soak: ok\n" : "soak: FAILED\n");
}

}  // namespace selfsense::soak
