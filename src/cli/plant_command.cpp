// `selfsense plant`: runs the simulated stack (selfsense::plant) over a generated or recorded
// excitation and writes a recording (docs/recording-format.md): measured t, E, D; the plant's true
// S and T as reference columns; temp where the temperature varies; the true terminal values (u, q,
// x, F: E_true, D_true, S, T through the geometry) and diagnostic columns (q_amp, p, status).
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "commands.hpp"
#include "selfsense/io/recording.hpp"
#include "selfsense/plant/excitation.hpp"
#include "selfsense/plant/plant.hpp"
#include "selfsense/plant_io/plant_recording.hpp"
#include "selfsense/plant_io/plant_yaml.hpp"
#include "selfsense/runtime/pacer.hpp"

namespace selfsense::cli {
namespace {

struct PlantOptions {
  std::filesystem::path config{};
  std::optional<std::uint64_t> seed{};
  std::string excitation{};
  std::filesystem::path out{};
  bool realtime{false};
};

// Steps the plant paced to its sample rate on the monotonic clock, as the daemon's simulated
// backend will; reports the overruns.
std::vector<plant::StepOutput> run_paced(const plant::PlantConfig& config,
                                         const std::vector<plant::StepInput>& inputs) {
  plant::Plant p(config);
  std::vector<plant::StepOutput> out(inputs.size());
  runtime::SteadyClock clock;
  runtime::Pacer pacer(clock, std::llround(1e9 / config.sample_rate_hz));
  pacer.start();
  for (std::size_t k = 0; k < inputs.size(); ++k) {
    out[k] = p.step(inputs[k]);
    static_cast<void>(pacer.wait());
  }
  const runtime::LatencyHistogram& wake = pacer.stats().wake_latency;
  std::printf(
      "selfsense plant: paced in real time, %lld overruns (worst %.1f us late), wake-up "
      "latency p99 %.1f us, max %.1f us\n",
      static_cast<long long>(pacer.overruns()), 1e-3 * static_cast<double>(pacer.worst_late_ns()),
      1e-3 * static_cast<double>(wake.percentile_ns(0.99)),
      1e-3 * static_cast<double>(wake.max_ns()));
  return out;
}

void run_plant(const PlantOptions& opt) {
  plant::PlantFile file = plant::load_plant_file(opt.config);
  if (opt.seed) file.plant.seed = *opt.seed;
  const double fs = file.plant.sample_rate_hz;

  plant::Excitation ex{};
  const std::string csv_prefix = "csv:";
  if (opt.excitation.starts_with(csv_prefix)) {
    ex = plant::read_excitation_csv(opt.excitation.substr(csv_prefix.size()), file.excitation, fs);
  } else {
    ex = plant::make_excitation(opt.excitation, file.excitation, fs, file.plant.seed);
  }

  const std::vector<plant::StepInput> inputs = ex.inputs();
  std::vector<plant::StepOutput> out =
      opt.realtime ? run_paced(file.plant, inputs) : plant::simulate(file.plant, inputs);
  const std::size_t n = out.size();
  std::ostringstream heading;
  heading << "selfsense plant: config " << opt.config.string() << ", excitation " << opt.excitation
          << ", seed " << file.plant.seed;
  const io::Recording rec = plant::plant_recording(file.plant, ex, std::move(out), heading.str());
  io::write_recording_csv(rec, opt.out);
  std::cout << "selfsense plant: wrote " << n << " samples (" << static_cast<double>(n) / fs
            << " s) to " << opt.out.string() << '\n';
}

}  // namespace

void add_plant_command(CLI::App& app) {
  auto opt = std::make_shared<PlantOptions>();
  CLI::App* cmd = app.add_subcommand(
      "plant", "simulate the piezo stack plant and write a recording with reference S and T");
  cmd->add_option("--config", opt->config, "plant configuration (YAML)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--seed", opt->seed, "overrides plant.seed");
  cmd->add_option(
         "--excitation", opt->excitation,
         "steps | sines | decaying | noise | loops | mix | identification (mix, then loops) | "
         "csv:PATH (E, optional F_ext and temp)")
      ->required();
  cmd->add_option("--out", opt->out, "recording to write (CSV)")->required();
  cmd->add_flag("--realtime", opt->realtime,
                "pace the plant to its sample rate on the monotonic clock (default: as fast as "
                "possible, simulated time)");
  cmd->callback([opt] { run_plant(*opt); });
}

}  // namespace selfsense::cli
