// `selfsense plant`: runs the simulated stack (selfsense::plant) over a generated or recorded
// excitation and writes a recording (contracts.md): measured t, E, D; the plant's true S and T
// as reference columns; temp where the temperature varies; the true terminal values (u, q, x, F:
// E_true, D_true, S, T through the geometry) and diagnostic columns (q_amp, p, status).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.hpp"
#include "selfsense/io/recording.hpp"
#include "selfsense/plant/excitation.hpp"
#include "selfsense/plant/plant.hpp"
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

// Linear interpolation of a recorded column onto the plant's sample grid.
std::vector<double> resample(std::span<const double> t, std::span<const double> v, double t0,
                             double fs, std::size_t n) {
  std::vector<double> out(n);
  std::size_t j = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const double tk = t0 + static_cast<double>(k) / fs;
    while (j + 2 < t.size() && t[j + 1] <= tk)
      ++j;
    const double f = std::clamp((tk - t[j]) / (t[j + 1] - t[j]), 0.0, 1.0);
    out[k] = v[j] + f * (v[j + 1] - v[j]);
  }
  return out;
}

// E (V/m) and optionally F_ext (N, external force on the stack; F in our recordings is the
// stack force T A) and temp (degC) from a recording.
plant::Excitation read_excitation_csv(const std::filesystem::path& path,
                                      const plant::ExcitationConfig& config, double fs) {
  const io::Recording rec = io::read_recording_csv(path, io::ReadOptions{{"t", "E"}});
  if (rec.rows() < 2) throw std::runtime_error{path.string() + ": needs at least two rows"};
  const auto t = rec.column("t");
  const auto n = static_cast<std::size_t>((t.back() - t.front()) * fs) + 1;
  plant::Excitation ex{};
  ex.e_v_per_m = resample(t, rec.column("E"), t.front(), fs, n);
  plant::apply_load_and_temperature(config, fs, ex);
  if (rec.has("F_ext")) ex.force_n = resample(t, rec.column("F_ext"), t.front(), fs, n);
  if (rec.has("temp")) ex.temp_degc = resample(t, rec.column("temp"), t.front(), fs, n);
  return ex;
}

void run_plant(const PlantOptions& opt) {
  plant::PlantFile file = plant::load_plant_file(opt.config);
  if (opt.seed) file.plant.seed = *opt.seed;
  const double fs = file.plant.sample_rate_hz;

  plant::Excitation ex{};
  const std::string csv_prefix = "csv:";
  if (opt.excitation.starts_with(csv_prefix)) {
    ex = read_excitation_csv(opt.excitation.substr(csv_prefix.size()), file.excitation, fs);
  } else {
    ex = plant::make_excitation(opt.excitation, file.excitation, fs, file.plant.seed);
  }

  const std::vector<plant::StepInput> inputs = ex.inputs();
  std::vector<plant::StepOutput> out =
      opt.realtime ? run_paced(file.plant, inputs) : plant::simulate(file.plant, inputs);
  // Recordings hold finite numbers only (contracts.md): a NaN fault keeps its status bit and
  // repeats the previous delivered value in the file.
  for (std::size_t k = 0; k < out.size(); ++k) {
    plant::StepOutput& o = out[k];
    const plant::StepOutput* previous = k > 0 ? &out[k - 1] : nullptr;
    if (!std::isfinite(o.e_meas_v_per_m))
      o.e_meas_v_per_m = previous ? previous->e_meas_v_per_m : 0.0;
    if (!std::isfinite(o.d_meas_c_per_m2))
      o.d_meas_c_per_m2 = previous ? previous->d_meas_c_per_m2 : 0.0;
  }
  const plant::Derived derived = plant::derive(file.plant);

  io::Recording rec{};
  std::ostringstream line;
  line << "selfsense plant: config " << opt.config.string() << ", excitation " << opt.excitation
       << ", seed " << file.plant.seed;
  rec.comments.push_back(line.str());
  line.str("");
  line << "sample_rate_hz: " << fs;
  rec.comments.push_back(line.str());
  line.str("");
  line << "geometry: layers " << file.plant.geometry.layers << ", layer_thickness_m "
       << file.plant.geometry.layer_thickness_m << ", electrode_area_m2 "
       << file.plant.geometry.electrode_area_m2 << ", cross_section_m2 "
       << file.plant.geometry.cross_section_m2 << ", length_m " << derived.length_m
       << ", capacitance_f " << derived.capacitance_f;
  rec.comments.push_back(line.str());
  rec.comments.emplace_back(
      "columns: t s, E V/m (measured), D C/m^2 (measured), S - and T Pa (plant truth), "
      "temp degC, E_true V/m, D_true C/m^2, u V, q C, x m, F N (true terminal values: "
      "u = E_true h, q = D_true n A_el, x = S L, F = T A_mech), q_amp C (charge amplifier "
      "output before delay and ADC), p (Preisach state), status (StatusFlag bits; a NaN sample "
      "repeats the previous value)");

  const std::size_t n = out.size();
  auto column = [&out, n](auto member) {
    std::vector<double> v(n);
    for (std::size_t k = 0; k < n; ++k)
      v[k] = member(out[k]);
    return v;
  };
  using Out = plant::StepOutput;
  rec.set_column("t", column([](const Out& o) { return o.t_s; }));
  rec.set_column("E", column([](const Out& o) { return o.e_meas_v_per_m; }));
  rec.set_column("D", column([](const Out& o) { return o.d_meas_c_per_m2; }));
  rec.set_column("S", column([](const Out& o) { return o.s; }));
  rec.set_column("T", column([](const Out& o) { return o.t_pa; }));
  const auto [tmin, tmax] = std::minmax_element(ex.temp_degc.begin(), ex.temp_degc.end());
  // The stack's temperature: the input's, which self-heating raises.
  if ((tmin != ex.temp_degc.end() && *tmin != *tmax) || file.plant.heating.enabled) {
    rec.set_column("temp", column([](const Out& o) { return o.temp_degc; }));
  }
  rec.set_column("u", column([](const Out& o) { return o.u_v; }));
  rec.set_column("q", column([](const Out& o) { return o.q_c; }));
  rec.set_column("x", column([](const Out& o) { return o.x_m; }));
  rec.set_column("F", column([](const Out& o) { return o.f_n; }));
  rec.set_column("E_true", column([](const Out& o) { return o.e_v_per_m; }));
  rec.set_column("D_true", column([](const Out& o) { return o.d_c_per_m2; }));
  rec.set_column("q_amp", column([](const Out& o) { return o.q_amp_c; }));
  rec.set_column("p", column([](const Out& o) { return o.polarisation; }));
  rec.set_column("status", column([](const Out& o) { return static_cast<double>(o.status); }));
  if (std::any_of(out.begin(), out.end(), [](const Out& o) { return o.latency_s > 0.0; })) {
    rec.set_column("latency_s", column([](const Out& o) { return o.latency_s; }));
  }
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
