// Fuzz target: the daemon's configuration (daemon/config.hpp) with the driver registry reading
// the driver section (simulated, can, modbus-tcp, modbus-rtu), as `selfsense check-config` does.
// The file sits in a scratch directory beside copies of config/models/sim.yaml and
// config/plant/daemon.yaml, so the relative paths of config/sim.yaml resolve and a valid file is
// accepted.
// Properties:
//  - load_config never throws;
//  - every problem starts with "FILE:LINE: " (docs/daemon.md, "Start": `FILE:LINE: KEY.PATH: what`)
//  and is
//    one line;
//  - an accepted configuration has a loop config the loop takes (rate and sample time finite and
//    positive) and the registry builds its driver's configuration without an exception.
#include <cmath>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <string>

#include "fuzz_check.hpp"
#include "selfsense/daemon/config.hpp"
#include "selfsense/drivers/registry/registry.hpp"

namespace {

const selfsense::fuzz::ScratchFile& scratch() {
  static const selfsense::fuzz::ScratchFile file("config.yaml");
  static const bool copied = [] {
    const std::filesystem::path config = std::filesystem::path(SELFSENSE_SOURCE_DIR) / "config";
    for (const char* relative : {"models/sim.yaml", "plant/daemon.yaml"}) {
      const std::filesystem::path to = file.directory() / relative;
      std::filesystem::create_directories(to.parent_path());
      std::filesystem::copy_file(config / relative, to,
                                 std::filesystem::copy_options::overwrite_existing);
    }
    return true;
  }();
  static_cast<void>(copied);
  return file;
}

}  // namespace

// NOLINTNEXTLINE(readability-identifier-naming): the name libFuzzer calls.
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using selfsense::fuzz::require;
  const selfsense::fuzz::ScratchFile& input = scratch();
  input.write(selfsense::fuzz::as_text(data, size));
  const std::string file = input.path().string();

  selfsense::drivers::Registry registry;
  selfsense::daemon::ConfigResult result;
  try {
    result = selfsense::daemon::load_config(input.path(), &registry);
  } catch (const std::exception& e) {
    selfsense::fuzz::violated("load_config never throws", e.what());
  }
  for (const std::string& problem : result.problems) {
    require(selfsense::fuzz::names_file_and_line(problem, file),
            "every configuration problem names the file and line", problem);
    require(problem.find('\n') == std::string::npos, "every problem is one line", problem);
  }
  if (!result.ok()) return 0;
  const double ts = result.config.sample_time();
  require(std::isfinite(ts) && ts > 0.0, "an accepted configuration has a sample time");
  try {
    static_cast<void>(result.config.loop_config());
  } catch (const std::exception& e) {
    selfsense::fuzz::violated("an accepted configuration gives the loop's configuration", e.what());
  }
  return 0;
}
