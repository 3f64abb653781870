// `selfsense sim-device --can IFACE`: the simulated transducer (selfsense::plant) served as a CAN
// node (docs/drivers/can.md), the far end of the CAN driver (drivers/can). Not part
// of the daemon. The command reads the daemon configuration (the frame layout) and the plant's
// file; this library serves them.
#pragma once

#include "selfsense/drivers/can/can_config.hpp"
#include "selfsense/plant/config.hpp"

namespace selfsense::drivers::can_sim {

struct CanSimDeviceOptions {
  can::CanConfig layout{};           // the daemon's driver section; layout.interface: the bus
  plant::PlantConfig plant{};        // checked here ("--plant: ..." when not valid)
  double rate_hz{1000.0};            // input frames per second, paced in real time
  double duration_s{0.0};            // 0: until SIGINT or SIGTERM
  double command_timeout_ms{100.0};  // no command for this long: the node applies E = 0
};

// Runs until SIGINT/SIGTERM (or the duration); prints one summary line on stdout. Returns the
// process exit status: 0 after a clean stop, 1 on a setup error (printed on stderr).
int run_can_sim_device(const CanSimDeviceOptions& options);

}  // namespace selfsense::drivers::can_sim
