// Sub-commands of the `selfsense` tool. Each file registers one sub-command on the app and
// runs it; main() only dispatches.
#pragma once

namespace CLI {
class App;
}  // namespace CLI

namespace selfsense::cli {

void add_demo_command(CLI::App& app);
void add_plant_command(CLI::App& app);
void add_identify_command(CLI::App& app);
void add_simulate_command(CLI::App& app);
void add_reconstruct_command(CLI::App& app);
void add_feedforward_command(CLI::App& app);
void add_import_command(CLI::App& app);
void add_check_config_command(CLI::App& app);

}  // namespace selfsense::cli
