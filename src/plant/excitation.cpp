#include "selfsense/plant/excitation.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include "checker.hpp"
#include "selfsense/plant/random.hpp"

namespace selfsense::plant {

namespace {

std::size_t samples(double seconds, double sample_rate_hz) {
  return static_cast<std::size_t>(std::llround(std::max(seconds, 0.0) * sample_rate_hz));
}

void ramp(std::vector<double>& out, double from, double to, double seconds, double fs) {
  const std::size_t n = samples(seconds, fs);
  for (std::size_t i = 0; i < n; ++i) {
    out.push_back(from + (to - from) * static_cast<double>(i + 1) / static_cast<double>(n));
  }
}

void sine(std::vector<double>& out, double offset, double amplitude, double frequency,
          double decay_per_cycle, int cycles, double fs) {
  const std::size_t n = samples(cycles / frequency, fs);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) / fs;
    const double envelope = std::pow(decay_per_cycle, t * frequency);
    out.push_back(offset + amplitude * envelope * std::sin(2.0 * std::numbers::pi * frequency * t));
  }
}

using detail::Checker;

}  // namespace

bool ExcitationConfig::is_valid(std::string* why) const {
  Checker c{why, "excitation."};
  for (std::size_t i = 0; i < steps.levels_v_per_m.size(); ++i) {
    c.finite("steps.levels_v_per_m[" + std::to_string(i) + "]", steps.levels_v_per_m[i]);
  }
  c.positive("steps.hold_s", steps.hold_s);
  for (std::size_t i = 0; i < sines.amplitudes_v_per_m.size(); ++i) {
    c.finite("sines.amplitudes_v_per_m[" + std::to_string(i) + "]", sines.amplitudes_v_per_m[i]);
  }
  for (std::size_t i = 0; i < sines.frequencies_hz.size(); ++i) {
    c.positive("sines.frequencies_hz[" + std::to_string(i) + "]", sines.frequencies_hz[i]);
  }
  c.finite("sines.offset_v_per_m", sines.offset_v_per_m);
  c.require(sines.cycles >= 1, "sines.cycles", sines.cycles, "must be >= 1");
  c.require(std::isfinite(sines.ramp_s) && sines.ramp_s >= 0.0, "sines.ramp_s", sines.ramp_s,
            "must be a finite number >= 0");
  c.finite("decaying.amplitude_v_per_m", decaying.amplitude_v_per_m);
  c.finite("decaying.offset_v_per_m", decaying.offset_v_per_m);
  c.positive("decaying.frequency_hz", decaying.frequency_hz);
  c.require(decaying.decay_per_cycle > 0.0 && decaying.decay_per_cycle <= 1.0,
            "decaying.decay_per_cycle", decaying.decay_per_cycle, "must be in (0, 1]");
  c.require(decaying.cycles >= 1, "decaying.cycles", decaying.cycles, "must be >= 1");
  c.require(std::isfinite(decaying.ramp_s) && decaying.ramp_s >= 0.0, "decaying.ramp_s",
            decaying.ramp_s, "must be a finite number >= 0");
  c.positive("noise.duration_s", noise.duration_s);
  c.positive("noise.cutoff_hz", noise.cutoff_hz);
  c.require(std::isfinite(noise.std_v_per_m) && noise.std_v_per_m >= 0.0, "noise.std_v_per_m",
            noise.std_v_per_m, "must be >= 0");
  c.finite("noise.offset_v_per_m", noise.offset_v_per_m);
  c.finite("noise.min_v_per_m", noise.min_v_per_m);
  c.require(std::isfinite(noise.max_v_per_m) && noise.max_v_per_m > noise.min_v_per_m,
            "noise.max_v_per_m", noise.max_v_per_m, "must be above noise.min_v_per_m");
  c.positive("loops.duration_s", loops.duration_s);
  c.finite("loops.min_v_per_m", loops.min_v_per_m);
  c.require(std::isfinite(loops.max_v_per_m) && loops.max_v_per_m > loops.min_v_per_m,
            "loops.max_v_per_m", loops.max_v_per_m, "must be above loops.min_v_per_m");
  c.positive("loops.rate_min_v_per_m_s", loops.rate_min_v_per_m_s);
  c.require(std::isfinite(loops.rate_max_v_per_m_s) &&
                loops.rate_max_v_per_m_s >= loops.rate_min_v_per_m_s,
            "loops.rate_max_v_per_m_s", loops.rate_max_v_per_m_s,
            "must be at least loops.rate_min_v_per_m_s");
  c.require(std::isfinite(loops.hold_max_s) && loops.hold_max_s >= 0.0, "loops.hold_max_s",
            loops.hold_max_s, "must be a finite number >= 0");
  c.finite("load.offset_n", load.offset_n);
  c.finite("load.amplitude_n", load.amplitude_n);
  c.positive("load.frequency_hz", load.frequency_hz);
  c.finite("temperature.start_degc", temperature.start_degc);
  c.finite("temperature.end_degc", temperature.end_degc);
  return c.ok();
}

std::vector<StepInput> Excitation::inputs() const {
  std::vector<StepInput> in(e_v_per_m.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    in[i].e_cmd_v_per_m = e_v_per_m[i];
    if (i < force_n.size()) in[i].force_n = force_n[i];
    if (i < temp_degc.size()) in[i].temp_degc = temp_degc[i];
  }
  return in;
}

std::vector<double> make_steps(const StepsConfig& config, double sample_rate_hz) {
  std::vector<double> out;
  const std::size_t hold = samples(config.hold_s, sample_rate_hz);
  out.insert(out.end(), hold, 0.0);
  for (const double level : config.levels_v_per_m)
    out.insert(out.end(), hold, level);
  return out;
}

std::vector<double> make_sines(const SinesConfig& config, double sample_rate_hz) {
  std::vector<double> out;
  for (const double f : config.frequencies_hz) {
    for (const double a : config.amplitudes_v_per_m) {
      ramp(out, 0.0, config.offset_v_per_m, config.ramp_s, sample_rate_hz);
      sine(out, config.offset_v_per_m, a, f, 1.0, config.cycles, sample_rate_hz);
      ramp(out, config.offset_v_per_m, 0.0, config.ramp_s, sample_rate_hz);
    }
  }
  return out;
}

std::vector<double> make_decaying(const DecayingConfig& config, double sample_rate_hz) {
  std::vector<double> out;
  ramp(out, 0.0, config.offset_v_per_m, config.ramp_s, sample_rate_hz);
  sine(out, config.offset_v_per_m, config.amplitude_v_per_m, config.frequency_hz,
       config.decay_per_cycle, config.cycles, sample_rate_hz);
  ramp(out, config.offset_v_per_m, 0.0, config.ramp_s, sample_rate_hz);
  return out;
}

std::vector<double> make_noise(const NoiseConfig& config, double sample_rate_hz,
                               std::uint64_t seed) {
  const std::size_t n = samples(config.duration_s, sample_rate_hz);
  Random random{seed ^ 0x9E3779B97F4A7C15ULL};
  const double a = -std::expm1(-2.0 * std::numbers::pi * config.cutoff_hz / sample_rate_hz);
  std::vector<double> out(n);
  double y1 = 0.0;
  double y2 = 0.0;
  double sum = 0.0;
  double sum2 = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    y1 += a * (random.gaussian() - y1);
    y2 += a * (y1 - y2);
    out[i] = y2;
    sum += y2;
    sum2 += y2 * y2;
  }
  const double count = std::max(static_cast<double>(n), 1.0);
  const double mean = sum / count;
  const double sd = std::sqrt(std::max(sum2 / count - mean * mean, 1e-300));
  for (double& v : out) {
    v = std::clamp(config.offset_v_per_m + config.std_v_per_m * (v - mean) / sd, config.min_v_per_m,
                   config.max_v_per_m);
  }
  return out;
}

std::vector<double> make_loops(const LoopsConfig& config, double sample_rate_hz,
                               std::uint64_t seed) {
  const std::size_t n = samples(config.duration_s, sample_rate_hz);
  Random random{seed ^ 0x5851F42D4C957F2DULL};
  std::vector<double> out;
  out.reserve(n);
  double level = config.min_v_per_m;
  bool rising = true;
  while (out.size() < n) {
    const double limit = rising ? config.max_v_per_m : config.min_v_per_m;
    const double u = random.uniform();
    const double next = level + (limit - level) * u * u;
    const double rate = config.rate_min_v_per_m_s +
                        (config.rate_max_v_per_m_s - config.rate_min_v_per_m_s) * random.uniform();
    ramp(out, level, next, std::abs(next - level) / rate, sample_rate_hz);
    if (random.uniform() < 1.0 / 3.0) {
      out.insert(out.end(), samples(config.hold_max_s * random.uniform(), sample_rate_hz), next);
    }
    level = next;
    rising = !rising;
  }
  out.resize(n);
  return out;
}

void apply_load_and_temperature(const ExcitationConfig& config, double sample_rate_hz,
                                Excitation& excitation) {
  const std::size_t n = excitation.size();
  excitation.force_n.resize(n);
  excitation.temp_degc.resize(n);
  const LoadConfig& load = config.load;
  const TemperatureProfileConfig& temp = config.temperature;
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) / sample_rate_hz;
    excitation.force_n[i] =
        load.offset_n + load.amplitude_n * std::sin(2.0 * std::numbers::pi * load.frequency_hz * t);
    const double fraction = n > 1 ? static_cast<double>(i) / static_cast<double>(n - 1) : 0.0;
    excitation.temp_degc[i] = temp.start_degc + (temp.end_degc - temp.start_degc) * fraction;
  }
}

Excitation make_excitation(const std::string& kind, const ExcitationConfig& config,
                           double sample_rate_hz, std::uint64_t seed) {
  constexpr std::array<std::string_view, 7> kKinds{"steps", "sines", "decaying",      "noise",
                                                   "loops", "mix",   "identification"};
  if (std::find(kKinds.begin(), kKinds.end(), kind) == kKinds.end()) {
    throw std::invalid_argument{
        "unknown excitation '" + kind +
        "' (steps, sines, decaying, noise, loops, mix, identification or csv:PATH)"};
  }
  Excitation ex{};
  auto append = [&ex](const std::vector<double>& part) {
    ex.e_v_per_m.insert(ex.e_v_per_m.end(), part.begin(), part.end());
  };
  const bool mix = kind == "mix" || kind == "identification";
  if (kind == "steps" || mix) append(make_steps(config.steps, sample_rate_hz));
  if (kind == "sines" || mix) append(make_sines(config.sines, sample_rate_hz));
  if (kind == "decaying" || mix) append(make_decaying(config.decaying, sample_rate_hz));
  if (kind == "noise" || mix) append(make_noise(config.noise, sample_rate_hz, seed));
  if (kind == "loops" || kind == "identification") {
    append(make_loops(config.loops, sample_rate_hz, seed));
  }
  apply_load_and_temperature(config, sample_rate_hz, ex);
  return ex;
}

}  // namespace selfsense::plant
