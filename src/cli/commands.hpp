// Sub-commands of the `selfsense` tool. Each file registers one sub-command on the app and
// runs it; main() only dispatches.
#pragma once

namespace CLI {
class App;
}  // namespace CLI

namespace selfsense::cli {

// Thrown by a command that has said what it had to and ends with this exit status (main()
// returns it): `selfsense ctl` tells an error reply (1) from an unreachable daemon (2).
struct CommandExit {
  int status{0};
};

void add_demo_command(CLI::App& app);
void add_plant_command(CLI::App& app);
void add_identify_command(CLI::App& app);
void add_simulate_command(CLI::App& app);
void add_reconstruct_command(CLI::App& app);
void add_feedforward_command(CLI::App& app);
void add_import_command(CLI::App& app);
void add_check_config_command(CLI::App& app);
void add_ctl_command(CLI::App& app);
void add_diagnose_command(CLI::App& app);
void add_main_job_page_command(CLI::App& app);
void add_sim_device_command(CLI::App& app);

}  // namespace selfsense::cli
