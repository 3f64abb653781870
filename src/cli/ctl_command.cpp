// `selfsense ctl`: the daemon's control-socket client (docs/control-socket.md). Builds one
// request, sends it, prints the daemon's JSON reply on stdout. Exit status: 0 when the reply
// is ok, 1 when it is an error (or the request could not be built from the arguments), 2 when
// the daemon could not be reached or did not answer in time.
//
// The client stays thin: the daemon validates every request against its limits and names the
// member at fault, so options are passed on as given and defaults are the daemon's.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.hpp"
#include "selfsense/daemon/control_client.hpp"
#include "selfsense/daemon/control_protocol.hpp"
#include "selfsense/importers/table_values.hpp"

namespace selfsense::cli {
namespace {

constexpr int kErrorReply = 1;
constexpr int kNoAnswer = 2;

struct CtlOptions {
  std::string socket{"/run/selfsensed/control.sock"};
  double timeout_s{5.0};
  bool pretty{false};
};

struct WaveOptions {
  std::string shape{};
  double amplitude{0.0};
  double offset{0.0};
  double frequency{0.0};
  double phase{0.0};
  std::uint64_t repeat{0};
  std::string levels{};
  double dwell{0.0};
  std::filesystem::path table{};
  double dt{0.0};
  // Which options were given: only those are sent.
  std::vector<std::pair<CLI::Option*, std::string>> given{};
};

// Sends the request and prints the reply; ends the command with its exit status.
void send_request(const CtlOptions& options, const nlohmann::json& request) {
  std::string line;
  try {
    const auto timeout = std::chrono::milliseconds(std::llround(options.timeout_s * 1000.0));
    daemon::ControlClient client(options.socket, timeout);
    line = client.exchange(request.dump());
  } catch (const daemon::ControlClientError& e) {
    std::cerr << "selfsense ctl: " << e.what() << '\n';
    throw CommandExit{kNoAnswer};
  }
  const nlohmann::json reply = nlohmann::json::parse(line, nullptr, false);
  const auto ok = reply.is_object() ? reply.find("ok") : reply.end();
  if (!reply.is_object() || ok == reply.end() || !ok->is_boolean()) {
    std::cerr << "selfsense ctl: the reply from " << options.socket
              << " is not a protocol reply: " << line.substr(0, 200) << '\n';
    throw CommandExit{kNoAnswer};
  }
  std::cout << (options.pretty ? reply.dump(2, ' ', false, nlohmann::json::error_handler_t::replace)
                               : line)
            << '\n'
            << std::flush;
  if (!ok->get<bool>()) throw CommandExit{kErrorReply};
}

nlohmann::json wave_request(const WaveOptions& wave) {
  nlohmann::json request = {{"request", "wave"}, {"shape", wave.shape}};
  for (const auto& [option, member] : wave.given) {
    if (option->count() == 0) continue;
    if (member == "amplitude") request[member] = wave.amplitude;
    if (member == "offset") request[member] = wave.offset;
    if (member == "frequency_hz") request[member] = wave.frequency;
    if (member == "phase") request[member] = wave.phase;
    if (member == "repeat") request[member] = wave.repeat;
    if (member == "levels") request[member] = importers::parse_number_list(wave.levels, "--levels");
    if (member == "dwell_s") request[member] = wave.dwell;
    if (member == "values") request[member] = importers::read_table_values(wave.table);
    if (member == "dt_s") request[member] = wave.dt;
  }
  return request;
}

void add_bare(CLI::App& ctl, const std::shared_ptr<CtlOptions>& options, const char* name,
              const char* what, const daemon::Request& request) {
  CLI::App* sub = ctl.add_subcommand(name, what);
  sub->fallthrough();
  sub->callback([options, request] { send_request(*options, daemon::to_json(request)); });
}

void add_wave(CLI::App& ctl, const std::shared_ptr<CtlOptions>& options) {
  auto wave = std::make_shared<WaveOptions>();
  CLI::App* sub = ctl.add_subcommand("wave", "Play a setpoint waveform, or stop it");
  sub->fallthrough();
  sub->add_option("shape", wave->shape, "sine | triangle | square | staircase | table | stop")
      ->required()
      ->check(CLI::IsMember({"sine", "triangle", "square", "staircase", "table", "stop"}));
  const auto given = [&](CLI::Option* option, const char* member) {
    wave->given.emplace_back(option, member);
  };
  given(sub->add_option("--amplitude", wave->amplitude,
                        "Amplitude in the mode's unit (staircase, table: a factor, default 1)"),
        "amplitude");
  given(sub->add_option("--offset", wave->offset, "Offset in the mode's unit (default 0)"),
        "offset");
  given(sub->add_option("--frequency", wave->frequency,
                        "Frequency [Hz]; staircase, table: 0 or absent plays the natural period"),
        "frequency_hz");
  given(sub->add_option("--phase", wave->phase, "Start phase [cycles] in [0, 1)"), "phase");
  given(sub->add_option("--repeat", wave->repeat, "Periods to play; 0 = forever (default)"),
        "repeat");
  given(sub->add_option("--levels", wave->levels, "Staircase levels, e.g. 0,2e-4,4e-4"), "levels");
  given(sub->add_option("--dwell", wave->dwell, "Staircase: seconds per level"), "dwell_s");
  given(sub->add_option("--table", wave->table,
                        "Table: one value per line, or a CSV with a 'value' column")
            ->check(CLI::ExistingFile),
        "values");
  given(sub->add_option("--dt", wave->dt, "Table: seconds between values"), "dt_s");
  sub->callback([options, wave] {
    nlohmann::json request;
    try {
      request = wave_request(*wave);
    } catch (const std::runtime_error& e) {
      std::cerr << "selfsense ctl: " << e.what() << '\n';
      throw CommandExit{kErrorReply};
    }
    send_request(*options, request);
  });
}

}  // namespace

void add_ctl_command(CLI::App& app) {
  auto options = std::make_shared<CtlOptions>();
  CLI::App* ctl = app.add_subcommand("ctl", "Talk to the running daemon over its control socket");
  ctl->add_option("--socket", options->socket, "The daemon's control socket")
      ->capture_default_str();
  ctl->add_option("--timeout", options->timeout_s, "Seconds to wait for the daemon")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  ctl->add_flag("--pretty", options->pretty, "Print the reply indented");
  ctl->require_subcommand(1);

  using daemon::RecordRequest;
  add_bare(*ctl, options, "status", "Print the daemon's status", daemon::StatusRequest{});
  add_bare(*ctl, options, "arm", "Arm the loop (from ready)", daemon::ArmRequest{});
  add_bare(*ctl, options, "disarm", "Disarm the loop: the amplifier goes to its safe output",
           daemon::DisarmRequest{});
  add_bare(*ctl, options, "reset",
           "Clear latched faults (faulted -> ready) and health warnings back in their bands",
           daemon::ResetRequest{});
  add_bare(*ctl, options, "reload", "Reload the parameters that are safe to change",
           daemon::ReloadRequest{});

  auto value = std::make_shared<double>(0.0);
  CLI::App* setpoint = ctl->add_subcommand(
      "setpoint", "Hold a setpoint: strain [-] in position mode, stress [Pa] in force mode");
  setpoint->fallthrough();
  setpoint->add_option("value", *value, "The setpoint in SI units")->required();
  setpoint->callback([options, value] {
    send_request(*options, daemon::to_json(daemon::SetpointRequest{*value}));
  });

  auto mode = std::make_shared<std::string>();
  CLI::App* mode_command = ctl->add_subcommand("mode", "Change the control mode");
  mode_command->fallthrough();
  mode_command->add_option("name", *mode, "position | force | open-loop | damping")->required();
  // Passed on as given, so that the daemon's message names a misspelt mode.
  mode_command->callback([options, mode] {
    send_request(*options, nlohmann::json{{"request", "mode"}, {"name", *mode}});
  });

  auto action = std::make_shared<std::string>();
  CLI::App* record = ctl->add_subcommand("record", "Start or stop the recorder");
  record->fallthrough();
  record->add_option("action", *action, "start | stop")
      ->required()
      ->check(CLI::IsMember({"start", "stop"}));
  record->callback([options, action] {
    const auto kind =
        *action == "start" ? RecordRequest::Action::kStart : RecordRequest::Action::kStop;
    send_request(*options, daemon::to_json(RecordRequest{kind}));
  });

  auto state_action = std::make_shared<std::string>();
  CLI::App* state =
      ctl->add_subcommand("state", "Dump the model's memory into the recorder's directory");
  state->fallthrough();
  state->add_option("action", *state_action, "save")->required()->check(CLI::IsMember({"save"}));
  state->callback([options] { send_request(*options, daemon::to_json(daemon::StateRequest{})); });

  auto adapt_action = std::make_shared<std::string>();
  CLI::App* adapt = ctl->add_subcommand(
      "adapt", "Freeze or resume the online drift estimate, or show it (docs/adaptation.md)");
  adapt->fallthrough();
  adapt->add_option("action", *adapt_action, "freeze | resume | show")
      ->required()
      ->check(CLI::IsMember({"freeze", "resume", "show"}));
  adapt->callback([options, adapt_action] {
    send_request(*options, nlohmann::json{{"request", "adapt"}, {"action", *adapt_action}});
  });

  auto force = std::make_shared<double>(0.0);
  auto duration = std::make_shared<double>(5e-4);
  CLI::App* impulse = ctl->add_subcommand(
      "impulse", "Push the stack with a force pulse from the bench (the simulated transducer)");
  impulse->fallthrough();
  impulse->add_option("force_n", *force, "The pulse's force [N]")->required();
  impulse->add_option("--duration", *duration, "The pulse's length [s]")->capture_default_str();
  impulse->callback([options, force, duration] {
    send_request(*options, daemon::to_json(daemon::ImpulseRequest{*force, *duration}));
  });

  add_wave(*ctl, options);
}

}  // namespace selfsense::cli
