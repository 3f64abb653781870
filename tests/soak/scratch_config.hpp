// The soak test's scratch files: a daemon configuration made from config/sim.yaml (the shipped
// simulated bench, with this run's paths, a small rotation size, recording from the start and
// the setpoint watchdog on) and a plant configuration made from config/plant/daemon.yaml with
// the fault schedule added. Made by editing the shipped files, key by key, so the soak runs the
// configuration users run; a key that is no longer there fails loudly.
#pragma once

#include <filesystem>
#include <string>

namespace selfsense::soak {

struct Scratch {
  std::filesystem::path directory{};  // everything below is in it
  std::filesystem::path config{};     // the daemon's configuration
  std::filesystem::path plant{};      // the simulated bench with the faults
  std::filesystem::path socket{};
  std::filesystem::path recordings{};
  std::filesystem::path prometheus{};
  double rate_hz{10000.0};
  double watchdog_s{0.5};
  std::size_t max_clients{16};
  std::size_t rotate_bytes{std::size_t{8} << 20U};
};

// Writes the plant file (config/plant/daemon.yaml with `faults_yaml` inside its plant section)
// and the daemon configuration with position gain kp and loop rate rate_hz. Throws
// std::runtime_error naming a key the shipped files no longer have.
[[nodiscard]] Scratch write_scratch(const std::filesystem::path& source_dir,
                                    const std::filesystem::path& directory,
                                    const std::string& faults_yaml, double kp, double rate_hz);

// Writes the daemon configuration again with another kp (a valid reload), atomically: written
// beside and renamed over, so a reload never reads half a file.
void write_daemon_config(const std::filesystem::path& source_dir, const Scratch& scratch,
                         double kp);

}  // namespace selfsense::soak
