// `selfsense check-config C.yaml` (docs/daemon.md): exit 0 and `ok` when the daemon
// would start with this file; otherwise one line per problem, `FILE:LINE: KEY.PATH: what`, and
// exit 1.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "commands.hpp"
#include "selfsense/daemon/config.hpp"
#include "selfsense/drivers/registry/registry.hpp"

namespace selfsense::cli {

void add_check_config_command(CLI::App& app) {
  auto path = std::make_shared<std::filesystem::path>();
  CLI::App* cmd = app.add_subcommand("check-config",
                                     "Validate a selfsensed configuration; print every problem");
  cmd->add_option("config", *path, "Daemon configuration (YAML)")->required();
  cmd->callback([path] {
    drivers::Registry registry;
    const daemon::ConfigResult result = daemon::load_config(*path, &registry);
    if (result.ok()) {
      std::printf("ok\n");
      return;
    }
    for (const std::string& p : result.problems)
      std::printf("%s\n", p.c_str());
    throw CommandExit{1};
  });
}

}  // namespace selfsense::cli
