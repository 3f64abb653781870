// `selfsense import`: brings recordings of other instruments into the CSV format of
// docs/recording-format.md. Sub-commands per source format: `aixacct` (aixACCT aixPlorer ASCII
// export) and `columns` (any delimited text).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>

#include "commands.hpp"
#include "selfsense/importers/import_aixacct.hpp"
#include "selfsense/importers/import_columns.hpp"
#include "selfsense/io/recording.hpp"

namespace selfsense::cli {

using importers::AixacctImport;
using importers::AixacctOptions;
using importers::ColumnsOptions;
using importers::import_aixacct;
using importers::import_columns;
using importers::parse_column_map;
namespace {

struct AixacctCommand {
  std::filesystem::path file{};
  std::filesystem::path out{};
  AixacctOptions options{};
  double area_mm2{0.0};
  double thickness_m{0.0};
  double current_offset_a{0.0};
  bool has_current_offset{false};
};

struct ColumnsCommand {
  std::filesystem::path file{};
  std::filesystem::path out{};
  std::string delimiter{","};
  std::string map{};
  ColumnsOptions options{};
};

void run_aixacct(AixacctCommand& cmd) {
  if (cmd.area_mm2 > 0.0) cmd.options.area_mm2 = cmd.area_mm2;
  if (cmd.thickness_m > 0.0) cmd.options.thickness_m = cmd.thickness_m;
  if (cmd.has_current_offset) cmd.options.current_offset_a = cmd.current_offset_a;
  if (cmd.has_current_offset && cmd.options.detrend_charge) {
    throw std::invalid_argument("--current-offset-a and --detrend-charge exclude each other");
  }
  const AixacctImport imported = import_aixacct(cmd.file, cmd.options);
  io::write_recording_csv(imported.recording, cmd.out);
  std::printf("wrote %s (%zu samples, block %d '%s', current offset %g A removed)\n",
              cmd.out.string().c_str(), imported.recording.rows(), cmd.options.block,
              imported.sample_name.c_str(), imported.offset_current_a);
}

void run_columns(ColumnsCommand& cmd) {
  cmd.options.delimiter = importers::parse_delimiter(cmd.delimiter);
  cmd.options.map = parse_column_map(cmd.map);
  const io::Recording rec = import_columns(cmd.file, cmd.options);
  io::write_recording_csv(rec, cmd.out);
  std::printf("wrote %s (%zu samples)\n", cmd.out.string().c_str(), rec.rows());
}

void add_aixacct(CLI::App& parent) {
  auto c = std::make_shared<AixacctCommand>();
  CLI::App* cmd = parent.add_subcommand(
      "aixacct", "aixACCT aixPlorer 'Export as ASCII' (.dat): one measurement block");
  cmd->add_option("file", c->file, "The .dat file")->required()->check(CLI::ExistingFile);
  cmd->add_option("--block", c->options.block, "Data block n ('Table n')")
      ->required()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--out", c->out, "Recording to write (CSV)")->required();
  cmd->add_option("--area-mm2", c->area_mm2, "Electrode area [mm^2] (else 'Area [mm2]')")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--thickness-m", c->thickness_m, "Thickness [m] (else 'Thickness [nm]')")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--current-offset-a", c->current_offset_a,
                  "Constant leakage current [A] to remove from D");
  cmd->add_flag("--detrend-charge", c->options.detrend_charge,
                "Remove the mean current of the block's last part (a final hold) from D");
  cmd->add_option("--detrend-tail", c->options.detrend_tail,
                  "Share of the block's samples at its end that --detrend-charge averages")
      ->check(CLI::Range(0.01, 1.0));
  cmd->callback([c, cmd] {
    c->has_current_offset = cmd->count("--current-offset-a") > 0;
    run_aixacct(*c);
  });
}

void add_columns(CLI::App& parent) {
  auto c = std::make_shared<ColumnsCommand>();
  ColumnsOptions& o = c->options;
  CLI::App* cmd = parent.add_subcommand("columns", "Delimited text: pick, name and scale columns");
  cmd->add_option("file", c->file, "The text file")->required()->check(CLI::ExistingFile);
  cmd->add_option("--map", c->map, "COLUMN:NAME[:UNIT],... e.g. \"2:t:s,3:x:um,4:u:V\"")
      ->required();
  cmd->add_option("--out", c->out, "Recording to write (CSV)")->required();
  cmd->add_option("--delimiter", c->delimiter, "One character, 'tab' or 'space' (default ',')");
  cmd->add_option("--skip-rows", o.skip_rows, "Lines to skip before the data (headers)");
  cmd->add_option("--first-row", o.first_row, "First data row to keep (1-based, after skipping)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--last-row", o.last_row, "Last data row to keep (default: the last)");
  cmd->add_option("--sample-rate-hz", o.sample_rate_hz, "Makes t where no column is named t")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--layer-thickness-m", o.layer_thickness_m, "E = u / h")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--electrode-area-m2", o.electrode_area_m2, "D = q / (A n)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--layers", o.layers, "n in D = q / (A n)")->check(CLI::Range(1.0, 1e6));
  cmd->add_option("--active-length-m", o.active_length_m, "S = x / L")->check(CLI::PositiveNumber);
  cmd->add_option("--cross-section-m2", o.cross_section_m2, "T = F / A_mech")
      ->check(CLI::PositiveNumber);
  cmd->callback([c] { run_columns(*c); });
}

}  // namespace

void add_import_command(CLI::App& app) {
  CLI::App* cmd =
      app.add_subcommand("import", "Convert a recording of another instrument to selfsense CSV");
  cmd->require_subcommand(1);
  add_aixacct(*cmd);
  add_columns(*cmd);
}

}  // namespace selfsense::cli
