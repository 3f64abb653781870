// selfsensed: the real-time self-sensing controller daemon (docs/daemon.md).
//   selfsensed --config C.yaml     foreground; systemd runs it as is (Type=notify)
// Exits non-zero with every configuration problem named when the file is bad.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <filesystem>

#include "selfsense/daemon/config.hpp"
#include "selfsense/daemon/daemon.hpp"
#include "selfsense/drivers/registry/registry.hpp"

int main(int argc, char** argv) {
  CLI::App app{"selfsensed: real-time self-sensing piezo controller"};
  std::filesystem::path config_path;
  app.add_option("--config", config_path, "Configuration (YAML)")->required();
  CLI11_PARSE(app, argc, argv);

  selfsense::drivers::Registry registry;
  const selfsense::daemon::ConfigResult config =
      selfsense::daemon::load_config(config_path, &registry);
  if (!config.ok()) {
    for (const std::string& p : config.problems)
      static_cast<void>(std::fprintf(stderr, "%s\n", p.c_str()));
    return 1;
  }
  try {
    selfsense::daemon::Daemon::block_signals();  // before any thread starts
    selfsense::daemon::Daemon daemon(config.config, registry.create(), registry);
    return daemon.run();
  } catch (const std::exception& e) {
    static_cast<void>(std::fprintf(stderr, "selfsensed: %s\n", e.what()));
    return 1;
  }
}
