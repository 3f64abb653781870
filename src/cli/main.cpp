// selfsense: the command-line tool. Sub-commands live in their own files (commands.hpp).
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

#include "commands.hpp"

int main(int argc, char** argv) {
  CLI::App app{"selfsense: self-sensing piezo actuator tools"};
  app.require_subcommand(1);
  selfsense::cli::add_demo_command(app);
  selfsense::cli::add_plant_command(app);
  selfsense::cli::add_identify_command(app);
  selfsense::cli::add_simulate_command(app);
  selfsense::cli::add_reconstruct_command(app);
  selfsense::cli::add_feedforward_command(app);
  selfsense::cli::add_import_command(app);
  selfsense::cli::add_check_config_command(app);
  selfsense::cli::add_ctl_command(app);
  selfsense::cli::add_diagnose_command(app);
  selfsense::cli::add_main_job_page_command(app);
  selfsense::cli::add_sim_device_command(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const selfsense::cli::CommandExit& e) {
    return e.status;
  } catch (const std::exception& e) {
    std::cerr << "selfsense: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
