#include "selfsense/plant_io/plant_recording.hpp"

#include <algorithm>
#include <cmath>
#include <span>
#include <sstream>
#include <stdexcept>

namespace selfsense::plant {
namespace {

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

}  // namespace

Excitation read_excitation_csv(const std::filesystem::path& path, const ExcitationConfig& config,
                               double sample_rate_hz) {
  const double fs = sample_rate_hz;
  const io::Recording rec = io::read_recording_csv(path, io::ReadOptions{{"t", "E"}});
  if (rec.rows() < 2) throw std::runtime_error{path.string() + ": needs at least two rows"};
  const auto t = rec.column("t");
  const auto n = static_cast<std::size_t>((t.back() - t.front()) * fs) + 1;
  Excitation ex{};
  ex.e_v_per_m = resample(t, rec.column("E"), t.front(), fs, n);
  apply_load_and_temperature(config, fs, ex);
  if (rec.has("F_ext")) ex.force_n = resample(t, rec.column("F_ext"), t.front(), fs, n);
  if (rec.has("temp")) ex.temp_degc = resample(t, rec.column("temp"), t.front(), fs, n);
  return ex;
}

io::Recording plant_recording(const PlantConfig& config, const Excitation& excitation,
                              std::vector<StepOutput> outputs, const std::string& heading) {
  std::vector<StepOutput>& out = outputs;
  for (std::size_t k = 0; k < out.size(); ++k) {
    StepOutput& o = out[k];
    const StepOutput* previous = k > 0 ? &out[k - 1] : nullptr;
    if (!std::isfinite(o.e_meas_v_per_m))
      o.e_meas_v_per_m = previous ? previous->e_meas_v_per_m : 0.0;
    if (!std::isfinite(o.d_meas_c_per_m2))
      o.d_meas_c_per_m2 = previous ? previous->d_meas_c_per_m2 : 0.0;
  }
  const Derived derived = derive(config);

  io::Recording rec{};
  rec.comments.push_back(heading);
  std::ostringstream line;
  line << "sample_rate_hz: " << config.sample_rate_hz;
  rec.comments.push_back(line.str());
  line.str("");
  line << "geometry: layers " << config.geometry.layers << ", layer_thickness_m "
       << config.geometry.layer_thickness_m << ", electrode_area_m2 "
       << config.geometry.electrode_area_m2 << ", cross_section_m2 "
       << config.geometry.cross_section_m2 << ", length_m " << derived.length_m
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
  using Out = StepOutput;
  rec.set_column("t", column([](const Out& o) { return o.t_s; }));
  rec.set_column("E", column([](const Out& o) { return o.e_meas_v_per_m; }));
  rec.set_column("D", column([](const Out& o) { return o.d_meas_c_per_m2; }));
  rec.set_column("S", column([](const Out& o) { return o.s; }));
  rec.set_column("T", column([](const Out& o) { return o.t_pa; }));
  const std::vector<double>& temp = excitation.temp_degc;
  const auto [tmin, tmax] = std::minmax_element(temp.begin(), temp.end());
  // The stack's temperature: the input's, which self-heating raises.
  if ((tmin != temp.end() && *tmin != *tmax) || config.heating.enabled) {
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
  return rec;
}

}  // namespace selfsense::plant
