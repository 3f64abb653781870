#include "soak/scratch_config.hpp"

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace selfsense::soak {
namespace {

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path.string());
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void write_text(const std::filesystem::path& path, const std::string& text) {
  const std::filesystem::path temporary = path.string() + ".new";
  {
    std::ofstream out(temporary, std::ios::trunc);
    out << text;
    if (!out.flush()) throw std::runtime_error("cannot write " + temporary.string());
  }
  std::filesystem::rename(temporary, path);
}

// Replaces the value after `key` (a line's text up to its ':' and the space after it, indent
// included) up to the line's comment or end.
void set_value(std::string& text, const std::string& key, const std::string& value,
               const std::filesystem::path& file) {
  const std::string needle = "\n" + key;
  const std::size_t at = text.find(needle);
  if (at == std::string::npos || text.find(needle, at + 1) != std::string::npos) {
    throw std::runtime_error(file.string() + ": no single line starting '" + key + "'");
  }
  const std::size_t begin = at + needle.size();
  const std::size_t end_of_line = text.find('\n', begin);
  const std::size_t comment = text.find(" #", begin);
  const std::size_t end = comment < end_of_line ? comment : end_of_line;
  text.replace(begin, end - begin, value);
}

void replace_once(std::string& text, const std::string& from, const std::string& to,
                  const std::filesystem::path& file) {
  const std::size_t at = text.find(from);
  if (at == std::string::npos) throw std::runtime_error(file.string() + ": no '" + from + "'");
  text.replace(at, from.size(), to);
}

std::string daemon_config_text(const std::filesystem::path& source_dir, const Scratch& s,
                               double kp) {
  const std::filesystem::path shipped = source_dir / "config" / "sim.yaml";
  std::string text = read_text(shipped);
  set_value(text, "  rate_hz: ", std::to_string(static_cast<int>(s.rate_hz)), shipped);
  set_value(text, "model: ", (source_dir / "config" / "models" / "sim.yaml").string(), shipped);
  set_value(text, "  plant: ", s.plant.string(), shipped);
  set_value(text, "  watchdog_s: ", std::to_string(s.watchdog_s), shipped);
  set_value(text, "  directory: ", s.recordings.string(), shipped);
  set_value(text, "  rotate_bytes: ", std::to_string(s.rotate_bytes), shipped);
  set_value(text, "  flush_ms: ", "100", shipped);
  set_value(text, "  flight_recorder_s: ", "2", shipped);
  set_value(text, "  record_at_start: ", "true", shipped);
  set_value(text, "  path: ", s.socket.string(), shipped);
  set_value(text, "  max_clients: ", std::to_string(s.max_clients), shipped);
  set_value(text, "  prometheus_file: ", s.prometheus.string(), shipped);
  std::ostringstream gain;
  gain << "position: {kp: " << kp << ",";
  replace_once(text, "position: {kp: 2.0e8,", gain.str(), shipped);
  return "# scratch copy of config/sim.yaml for the soak test (tests/soak)\n" + text;
}

}  // namespace

Scratch write_scratch(const std::filesystem::path& source_dir,
                      const std::filesystem::path& directory, const std::string& faults_yaml,
                      double kp, double rate_hz) {
  Scratch s;
  s.rate_hz = rate_hz;
  s.directory = directory;
  s.config = directory / "soak.yaml";
  s.plant = directory / "plant.yaml";
  s.socket = directory / "control.sock";
  s.recordings = directory / "recordings";
  s.prometheus = directory / "selfsensed.prom";
  const std::filesystem::path bench = source_dir / "config" / "plant" / "daemon.yaml";
  std::string plant = read_text(bench);
  replace_once(plant, "\nexcitation:", "\n" + faults_yaml + "excitation:", bench);
  write_text(s.plant, plant);
  write_text(s.config, daemon_config_text(source_dir, s, kp));
  return s;
}

void write_daemon_config(const std::filesystem::path& source_dir, const Scratch& scratch,
                         double kp) {
  write_text(scratch.config, daemon_config_text(source_dir, scratch, kp));
}

}  // namespace selfsense::soak
