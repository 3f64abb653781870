// `selfsense identify`: fits a transducer model of a named structure to a recording with
// reference channels, on its first part, and reports the fit on that part and on the held-out
// rest (docs/recording-format.md).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.hpp"
#include "selfsense/adaptation/temperature_fit.hpp"
#include "selfsense/evaluation/field_signals.hpp"
#include "selfsense/evaluation/model_runs.hpp"
#include "selfsense/evaluation/work_runner.hpp"
#include "selfsense/identification/transducer_fit.hpp"
#include "selfsense/io/recording.hpp"
#include "selfsense/model_io/geometry_yaml.hpp"
#include "selfsense/model_io/model_yaml.hpp"

namespace selfsense::cli {

using evaluation::ChannelFigures;
using evaluation::describe;
using evaluation::field_signals;
using evaluation::FieldSignals;
using evaluation::figures;
using evaluation::ModelRuns;
using evaluation::run_model;
using evaluation::to_json;
namespace {

struct IdentifyOptions {
  std::filesystem::path recording{};
  std::string structure{};
  std::filesystem::path out{};
  std::filesystem::path json{};
  std::filesystem::path geometry{};
  std::filesystem::path validate{};
  double holdout{0.2};
  double fit_until{0.0};  // > 0: fit on t < fit_until instead of a share
  int plays{-1};
  int eigenvalues{-1};
  int creep_plays{-1};
  int dead_zones{-1};
  int bias_levels{-1};
  double fastest{0.0};
  double slowest{0.0};
  // Temperature coefficients (docs/adaptation.md): fitted on these recordings together (a ramp
  // with a temp column, or recordings at several temperatures), or on --recording itself when
  // its temp column spans at least 2 K.
  std::vector<std::filesystem::path> temperature_recordings{};
  std::string temperature_column{"temp"};
  double reference_degc{25.0};  // used when --recording has no temperature column
};

void print_table(const std::vector<ChannelFigures>& fit, const std::vector<ChannelFigures>& held) {
  std::printf("  channel   fit nrmse   fit max   held-out nrmse   held-out max\n");
  for (std::size_t i = 0; i < fit.size(); ++i) {
    std::printf("  %-7s %9.3f %% %7.3f %%", fit[i].channel.c_str(), 100.0 * fit[i].figures.nrmse,
                100.0 * fit[i].figures.max);
    if (i < held.size()) {
      std::printf(" %14.3f %% %12.3f %%", 100.0 * held[i].figures.nrmse,
                  100.0 * held[i].figures.max);
    }
    std::printf("\n");
  }
}

// What preisach-creep chose on the fitting data (transducer_fit.hpp), read off the model; `how`
// says whether they were chosen or given (--dead-zones, --bias-levels).
void print_chosen_sizes(const models::TransducerModel& model, const char* how) {
  const auto describe = [](const char* name, const std::optional<models::SideModel>& side) {
    if (!side) return;
    const auto& s = side->op.superposition;
    const std::size_t dead_zones = std::max(s.upper_thresholds.size(), s.lower_thresholds.size());
    std::vector<double> r = side->op.hinges.thresholds;
    const std::size_t hinges = r.size();
    std::sort(r.begin(), r.end());
    const auto plays = static_cast<std::size_t>(std::unique(r.begin(), r.end()) - r.begin());
    std::printf("  %s: %zu dead zones per side, %zu hinges per play (%zu hinges)\n", name,
                dead_zones, plays == 0 ? 0 : hinges / plays, hinges);
  };
  std::printf("sizes %s:\n", how);
  describe("sensor", model.sensor);
  describe("actuator", model.actuator);
}

// The temperature coefficients (adaptation/temperature_fit.hpp) on the recordings that have the
// temperature: --temperature-recording (one or several, fitted together), or the identification
// recording when its temperature column spans at least 2 K; the reference is the identification
// recording's mean temperature (or --reference-degc without one). Returns the JSON figures, or
// null when nothing was fitted.
nlohmann::json fit_temperature_coefficients(models::TransducerModel& model,
                                            const IdentifyOptions& opt, const io::Recording& rec,
                                            const FieldSignals& signals,
                                            const std::optional<models::Geometry>& geometry) {
  const auto column = [&opt](const io::Recording& r) {
    return r.has(opt.temperature_column) ? r.column(opt.temperature_column)
                                         : std::span<const double>{};
  };
  const std::span<const double> own = column(rec);
  double reference = opt.reference_degc;
  if (!own.empty()) {
    double sum = 0.0;
    for (const double v : own)
      sum += v;
    reference = sum / static_cast<double>(own.size());
  }
  const bool other = !opt.temperature_recordings.empty();
  std::vector<io::Recording> others;
  for (const std::filesystem::path& path : opt.temperature_recordings) {
    others.push_back(io::read_recording_csv(path, io::ReadOptions{{"t"}}));
    if (column(others.back()).empty()) {
      throw std::invalid_argument("--temperature-recording: " + path.string() + " has no column '" +
                                  opt.temperature_column + "'");
    }
  }
  if (own.empty() && !other) return nullptr;
  if (!other) {
    const auto [lo, hi] = std::minmax_element(own.begin(), own.end());
    if (*hi - *lo < 2.0) return nullptr;  // one temperature: nothing to fit
  }
  if (!model.sensor || !model.actuator || model.drive() != models::Drive::kField ||
      model.vectorial) {
    if (other) {
      throw std::invalid_argument(
          "--temperature-recording: the temperature coefficients need a field-driven structure "
          "with both sides");
    }
    std::printf("note: temperature column ignored: this structure has no coefficients per K\n");
    return nullptr;
  }
  // Each recording's signals (kept alive here: the fit's inputs are views of them).
  std::vector<std::string> names;
  std::vector<FieldSignals> signals_of;
  std::vector<std::span<const double>> temps;
  if (!other) {
    names.push_back(opt.recording.string());
    signals_of.push_back(signals);
    temps.push_back(own);
  }
  for (std::size_t i = 0; i < others.size(); ++i) {
    names.push_back(opt.temperature_recordings[i].string());
    signals_of.push_back(field_signals(others[i], names.back(), geometry, models::Drive::kField));
    temps.push_back(column(others[i]));
  }
  std::vector<adaptation::TemperatureFitInput> inputs;
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < names.size(); ++i) {
    const FieldSignals& fs = signals_of[i];
    if (fs.stress.empty() || fs.s.empty() || fs.e.empty() || fs.d.empty()) {
      throw std::invalid_argument("temperature coefficients: " + names[i] + " needs E, D, S and T");
    }
    inputs.push_back({fs.e, fs.d, fs.stress, fs.s, temps[i]});
    const auto [l, h] = std::minmax_element(temps[i].begin(), temps[i].end());
    lo = std::min(lo, *l);
    hi = std::max(hi, *h);
  }
  std::string name = names.front();
  for (std::size_t i = 1; i < names.size(); ++i)
    name += ", " + names[i];
  const adaptation::TemperatureFitResult fit =
      adaptation::fit_temperature(model, inputs, reference);
  model.temperature = fit.coefficients;
  const models::SideTemperature& se = fit.coefficients.sensor;
  const models::SideTemperature& ac = fit.coefficients.actuator;
  std::printf(
      "temperature coefficients from %s (%.1f .. %.1f degC, reference %.2f degC), per K and "
      "per K^2%s:\n"
      "  sensor   permittivity %+.3e %+.3e, loop %+.3e %+.3e, coupling   %+.3e %+.3e\n"
      "  actuator linear       %+.3e %+.3e, loop %+.3e %+.3e, compliance %+.3e %+.3e\n"
      "  residual RMS: D %.3g -> %.3g C/m^2, S %.3g -> %.3g\n"
      "  on the estimator's increments (%zu): permittivity %+.3e, loop %+.3e per K\n",
      name.c_str(), lo, hi, reference,
      fit.quadratic ? "" : " (first order: the temperature at fewer than three levels 2 K apart)",
      se.linear.per_k, se.linear.per_k2, se.loop.per_k, se.loop.per_k2, se.coupling.per_k,
      se.coupling.per_k2, ac.linear.per_k, ac.linear.per_k2, ac.loop.per_k, ac.loop.per_k2,
      ac.coupling.per_k, ac.coupling.per_k2, fit.sensor_rms_before, fit.sensor_rms_after,
      fit.actuator_rms_before, fit.actuator_rms_after, fit.increments,
      fit.coefficients.increments.linear_per_k, fit.coefficients.increments.loop_per_k);
  return {{"recording", name},
          {"reference_degc", reference},
          {"samples", fit.samples},
          {"quadratic", fit.quadratic},
          {"sensed_rms_before", fit.sensor_rms_before},
          {"sensed_rms_after", fit.sensor_rms_after},
          {"strain_rms_before", fit.actuator_rms_before},
          {"strain_rms_after", fit.actuator_rms_after},
          {"increments", fit.increments}};
}

void run_identify(const IdentifyOptions& opt) {
  const std::optional<models::Structure> structure = models::parse_structure(opt.structure);
  if (!structure) {
    throw std::invalid_argument("--structure: '" + opt.structure + "' is not one of " +
                                models::structure_names());
  }
  std::optional<models::Geometry> geometry;
  if (!opt.geometry.empty()) geometry = models::load_geometry(opt.geometry);
  const io::Recording rec = io::read_recording_csv(opt.recording, io::ReadOptions{{"t"}});
  const FieldSignals signals =
      field_signals(rec, opt.recording.string(), geometry, models::drive_of(*structure));
  const models::Drive drive = models::drive_of(*structure);
  const std::size_t n = signals.size();
  auto split = static_cast<std::size_t>(static_cast<double>(n) * (1.0 - opt.holdout));
  if (opt.fit_until > 0.0) {
    split = static_cast<std::size_t>(
        std::lower_bound(signals.t.begin(), signals.t.end(), opt.fit_until) - signals.t.begin());
  }
  if (split < 2)
    throw std::invalid_argument("--holdout or --fit-until leave fewer than 2 samples to fit");

  identification::IdentificationOptions sizes = identification::defaults_for(*structure);
  if (opt.plays >= 0) {
    sizes.plays = static_cast<std::size_t>(opt.plays);
    sizes.choose_plays = false;
  }
  if (opt.eigenvalues >= 0) sizes.eigenvalues = static_cast<std::size_t>(opt.eigenvalues);
  if (opt.creep_plays >= 0) sizes.creep_plays = static_cast<std::size_t>(opt.creep_plays);
  if (opt.dead_zones >= 0) {
    sizes.dead_zones = static_cast<std::size_t>(opt.dead_zones);
    sizes.choose_dead_zones = false;
  }
  if (opt.bias_levels >= 0) {
    sizes.bias_levels = static_cast<std::size_t>(opt.bias_levels);
    sizes.choose_bias_levels = false;
  }
  sizes.fastest_eigenvalue = opt.fastest;
  sizes.slowest_eigenvalue = opt.slowest;

  const auto head = [split](const std::vector<double>& v) {
    return v.empty() ? std::span<const double>{} : std::span<const double>(v).first(split);
  };
  const auto sensed = signals.sensed(drive);
  const identification::TransducerSignals part{
      signals.drive(drive).first(split), sensed.empty() ? sensed : sensed.first(split),
      head(signals.stress), head(signals.s), signals.sample_time};
  if (sensed.empty())
    std::printf("note: %s has no sensed channel: actuator side only\n", signals.source.c_str());
  if (signals.stress.empty()) {
    std::printf("note: %s has no T: free actuator assumed (T = 0); no stress reconstruction\n",
                signals.source.c_str());
  }
  const auto start = std::chrono::steady_clock::now();
  models::TransducerModel model =
      identification::identify(part, *structure, sizes, evaluation::run_on_threads);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  model.geometry = geometry;

  const ModelRuns runs = run_model(model, signals, true, true);
  const std::vector<ChannelFigures> fit = figures(model, signals, runs, 0, split);
  const std::vector<ChannelFigures> held = figures(model, signals, runs, split, n);
  std::printf(
      "selfsense identify: %s from %s (%zu samples, Ts %g s); fitted on the first %zu in "
      "%.2f s\n",
      opt.structure.c_str(), signals.source.c_str(), n, signals.sample_time, split, seconds);
  if (*structure == models::Structure::kPreisachCreep) {
    const char* how = "given (--dead-zones, --bias-levels)";
    if (sizes.choose_dead_zones && sizes.choose_bias_levels) {
      how = "chosen on the fitting data";
    } else if (sizes.choose_bias_levels) {
      how = "chosen on the fitting data (dead zones given)";
    } else if (sizes.choose_dead_zones) {
      how = "chosen on the fitting data (hinges given)";
    }
    print_chosen_sizes(model, how);
  }
  if (*structure == models::Structure::kStressHysteresis && sizes.choose_plays) {
    std::printf("sizes chosen on the fitting data: %zu plays\n",
                model.vectorial->basis.thresholds.size() - 1);
  }
  print_table(fit, held);

  nlohmann::json report = {{"structure", opt.structure},
                           {"recording", opt.recording.string()},
                           {"samples", n},
                           {"fit_samples", split},
                           {"sample_time_s", signals.sample_time},
                           {"seconds", seconds},
                           {"fit", to_json(fit)},
                           {"held_out", to_json(held)}};
  if (!runs.estimate_status.empty()) {
    report["estimate_status"] = to_json(runs.estimate_counts);
    if (runs.estimate_counts.not_ok() > 0) {
      std::printf("reconstruction status: %s\n", describe(runs.estimate_counts).c_str());
    }
  }
  // Couplings exist only when the recording had a stress channel.
  if (model.sensor && !model.sensor->linear_gains.empty()) {
    report["sensor_coupling"] = model.sensor->linear_gains.front();
  }
  if (model.actuator && !model.actuator->linear_gains.empty()) {
    report["actuator_coupling"] = model.actuator->linear_gains.front();
  }
  const nlohmann::json temperature =
      fit_temperature_coefficients(model, opt, rec, signals, geometry);
  if (!temperature.is_null()) report["temperature"] = temperature;
  models::save_model(model, opt.out,
                     "{fit: " + to_json(fit).dump() + ", held_out: " + to_json(held).dump() + "}");
  std::printf("wrote %s\n", opt.out.string().c_str());
  if (!opt.validate.empty()) {
    const io::Recording vrec = io::read_recording_csv(opt.validate, io::ReadOptions{{"t"}});
    const FieldSignals vsig = field_signals(vrec, opt.validate.string(), geometry, drive);
    const ModelRuns vruns = run_model(model, vsig, true, true);
    const std::vector<ChannelFigures> val = figures(model, vsig, vruns, 0, vsig.size());
    std::printf("validation on %s (%zu samples%s):\n", vsig.source.c_str(), vsig.size(),
                vruns.rediscretised ? ", model re-discretised for its sample time" : "");
    print_table(val, {});
    if (vruns.estimate_counts.not_ok() > 0) {
      std::printf("reconstruction status: %s\n", describe(vruns.estimate_counts).c_str());
    }
    report["validation"] = to_json(val);
  }
  if (!opt.json.empty()) {
    std::ofstream file(opt.json);
    if (!file || !(file << report.dump(2) << '\n')) {
      throw std::runtime_error(opt.json.string() + ": cannot write");
    }
    std::printf("wrote %s\n", opt.json.string().c_str());
  }
}

}  // namespace

void add_identify_command(CLI::App& app) {
  auto opt = std::make_shared<IdentifyOptions>();
  CLI::App* cmd = app.add_subcommand(
      "identify", "Fit a transducer model of a structure to a recording with reference S and T");
  cmd->add_option("--recording", opt->recording, "Recording (CSV)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--structure", opt->structure, models::structure_names())->required();
  cmd->add_option("--out", opt->out, "Model to write (YAML)")->required();
  cmd->add_option("--json", opt->json, "Fit figures to write (JSON)");
  cmd->add_option("--geometry", opt->geometry, "Transducer geometry (YAML), for u, q, x, F columns")
      ->check(CLI::ExistingFile);
  cmd->add_option("--validate", opt->validate, "A second recording to report the fit on")
      ->check(CLI::ExistingFile);
  cmd->add_option("--holdout", opt->holdout, "Share of the recording held out at its end")
      ->check(CLI::Range(0.0, 0.9));
  cmd->add_option("--fit-until", opt->fit_until, "Fit on t < this time [s]; the rest is held out")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--plays", opt->plays,
                  "Play operators (default per structure; stress-hysteresis chooses 16, 24 or "
                  "48 on the fitting data unless given)")
      ->check(CLI::Range(0, 512));
  cmd->add_option("--eigenvalues", opt->eigenvalues, "Creep eigenvalues")->check(CLI::Range(0, 32));
  cmd->add_option("--creep-plays", opt->creep_plays, "Creep elements on plays besides r = 0")
      ->check(CLI::Range(0, 64));
  cmd->add_option("--dead-zones", opt->dead_zones,
                  "Dead zones per side (preisach-creep chooses 0 or 8 on the fitting data unless "
                  "given)")
      ->check(CLI::Range(0, 64));
  cmd->add_option("--bias-levels", opt->bias_levels,
                  "Hinges per play (0: PI operator; preisach-creep chooses 0, 1, 3 or 7 on the "
                  "fitting data unless given)")
      ->check(CLI::Range(0, 32));
  cmd->add_option("--fastest-eigenvalue", opt->fastest, "Fastest creep eigenvalue [1/s]")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--slowest-eigenvalue", opt->slowest, "Slowest creep eigenvalue [1/s]")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--temperature-recording", opt->temperature_recordings,
                  "Recordings with a temperature column (a ramp, or recordings at several "
                  "temperatures; repeat or list them) to fit the temperature coefficients on "
                  "together (default: --recording, when its temperature varies by 2 K)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--temperature-column", opt->temperature_column,
                  "The temperature column [degC] (default temp)");
  cmd->add_option("--reference-degc", opt->reference_degc,
                  "The identification temperature when --recording has no temperature column");
  cmd->callback([opt] { run_identify(*opt); });
}

}  // namespace selfsense::cli
