// selfsense: the command-line tool. Sub-commands live in their own files (commands.hpp).
#include <malloc.h>

#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

#include "commands.hpp"

int main(int argc, char** argv) {
  // The fits (identify, diagnose, ...) allocate and free buffers of a few MB thousands of times
  // (Eigen's packing blocks for the normal equations, the regressor blocks). glibc's defaults
  // hand such blocks back to the kernel on free and fault fresh zeroed pages in on the next
  // allocation: the demo's identification took 4.3 million page faults, 28 s of kernel time.
  // Kept in the heap instead (blocks up to 32 MiB, 256 MiB of free heap before it is trimmed),
  // the same fits take 19 thousand; the results are the same, this being only where the memory
  // comes from. A short-lived tool; selfsensed keeps glibc's defaults.
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 256 << 20);
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
