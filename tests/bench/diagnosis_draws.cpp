// The diagnosis proof on the independent actuator (issue 23, item 4): draws per effect, each
// with its own stack, bench, effect form, magnitude, excitation and noise
// (tests/diagnosis/independent/), and the rates the proof judges. A plain program printing
// figures, not a pass/fail test: the thresholds are asserted in
// tests/diagnosis/independent_draws_test.cpp.
//
//   build/tests/bench/diagnosis_draws [--effect NAME|all] [--draws N] [--seed-base S]
//                                     [--threads T] [--evidence 1]
// --evidence 1 prints each finding's evidence under its draw's line.
//
// Defaults: all effects, 3 draws each, seed base 900000 (the development range), 1 thread.
// Draw i of an effect has seed S + i. One line per draw (effect, seed, ratio drawn -> achieved,
// verdict, findings, validation nrmse before/after/clean of D and S in %, excess ratio, pass,
// seconds; then the form with its numbers), then per effect: named on the right channel,
// excess <= 0.6, pass, and for `none` the share without findings and the share `consistent`.
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "diagnosis/independent/draws.hpp"

namespace {

using selfsense::independent::Effect;
using selfsense::independent::Outcome;

struct Arguments {
  std::vector<Effect> effects{selfsense::independent::kEffects.begin(),
                              selfsense::independent::kEffects.end()};
  std::uint64_t draws{3};
  std::uint64_t seed_base{900000};
  unsigned threads{1};
  bool evidence{false};  // each finding's evidence under its draw's line
};

[[noreturn]] void usage(const char* why) {
  static_cast<void>(
      std::fprintf(stderr,
                   "diagnosis_draws: %s\nusage: diagnosis_draws [--effect NAME|all] [--draws N] "
                   "[--seed-base S] [--threads T] [--evidence 1]\n",
                   why));
  std::exit(2);
}

std::uint64_t number(const char* text) {
  char* end = nullptr;
  const unsigned long long v = std::strtoull(text, &end, 10);
  if (end == text || *end != '\0') usage("not a number");
  return v;
}

Arguments parse(int argc, char** argv) {
  Arguments a;
  for (int i = 1; i < argc; ++i) {
    const std::string_view key = argv[i];
    if (i + 1 >= argc) usage("missing value");
    const char* value = argv[++i];
    if (key == "--effect") {
      if (std::string_view(value) == "all") continue;
      const auto e = selfsense::independent::parse_effect(value);
      if (!e) {
        usage(
            "unknown effect (none, creep, leakage, stress, temperature, dynamics, delay, "
            "creep_leakage, all)");
      }
      a.effects = {*e};
    } else if (key == "--draws") {
      a.draws = number(value);
    } else if (key == "--seed-base") {
      a.seed_base = number(value);
    } else if (key == "--evidence") {
      a.evidence = number(value) != 0;
    } else if (key == "--threads") {
      a.threads = static_cast<unsigned>(std::max<std::uint64_t>(1, number(value)));
    } else {
      usage("unknown option");
    }
  }
  return a;
}

double share(const std::vector<Outcome>& v, bool (*test)(const Outcome&)) {
  std::size_t n = 0;
  for (const Outcome& o : v) {
    if (test(o)) ++n;
  }
  return v.empty() ? 0.0 : 100.0 * static_cast<double>(n) / static_cast<double>(v.size());
}

void rates(Effect effect, const std::vector<Outcome>& v) {
  if (effect == Effect::kNone) {
    std::printf("%-13s %zu draws: no findings %.1f %%, consistent %.1f %%\n",
                selfsense::independent::to_string(effect), v.size(),
                share(v, [](const Outcome& o) { return o.findings.empty(); }),
                share(v, [](const Outcome& o) { return o.verdict == "consistent"; }));
    return;
  }
  std::printf("%-13s %zu draws: named right %.1f %%, excess <= 0.6 %.1f %%, pass %.1f %%\n",
              selfsense::independent::to_string(effect), v.size(),
              share(v, [](const Outcome& o) { return o.named_right; }),
              share(v, [](const Outcome& o) { return o.excess_ratio <= 0.6; }),
              share(v, [](const Outcome& o) { return o.pass; }));
}

}  // namespace

int main(int argc, char** argv) {
  const Arguments args = parse(argc, argv);
  const auto start = std::chrono::steady_clock::now();
  struct Job {
    Effect effect;
    std::uint64_t seed;
  };
  std::vector<Job> jobs;
  for (Effect e : args.effects) {
    for (std::uint64_t i = 0; i < args.draws; ++i)
      jobs.push_back({e, args.seed_base + i});
  }
  std::vector<Outcome> outcomes(jobs.size());
  std::vector<bool> done(jobs.size(), false);
  std::atomic<std::size_t> next{0};
  std::mutex print;
  const auto work = [&] {
    for (std::size_t i = next++; i < jobs.size(); i = next++) {
      try {
        Outcome o = selfsense::independent::run_draw(jobs[i].seed, jobs[i].effect);
        const std::lock_guard<std::mutex> lock(print);
        std::printf("%s\n", selfsense::independent::summary(o).c_str());
        if (args.evidence) {
          for (const selfsense::independent::Named& f : o.findings)
            std::printf("    %s %s: %s\n", f.effect.c_str(), f.channel.c_str(), f.evidence.c_str());
        }
        static_cast<void>(std::fflush(stdout));
        outcomes[i] = std::move(o);
        done[i] = true;
      } catch (const std::exception& ex) {  // counted as a failed draw
        const std::lock_guard<std::mutex> lock(print);
        std::printf("%-13s seed %llu | error: %s\n",
                    selfsense::independent::to_string(jobs[i].effect),
                    static_cast<unsigned long long>(jobs[i].seed), ex.what());
        outcomes[i].draw.effect = jobs[i].effect;
        outcomes[i].verdict = "error";
        outcomes[i].excess_ratio = std::nan("");
        done[i] = true;
      }
    }
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < args.threads; ++t)
    pool.emplace_back(work);
  work();
  for (std::thread& t : pool)
    t.join();

  std::printf("\n");
  for (Effect e : args.effects) {
    std::vector<Outcome> of;
    for (std::size_t i = 0; i < jobs.size(); ++i) {
      if (jobs[i].effect == e && done[i]) of.push_back(outcomes[i]);
    }
    rates(e, of);
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("elapsed %.1f s (%zu draws, %u threads)\n", seconds, jobs.size(), args.threads);
  return 0;
}
