#!/usr/bin/env bash
# Host side of payload/can_loop.sh: selfsensed with its SocketCAN driver against
# `selfsense sim-device --can` on vcan in the VM, both from this build's package installed with
# apt (position loop, injected frames counted, timeouts and safe output when the node dies, CAN FD).
#   tests/vm/can_loop.sh OUT_DIR   (after tests/vm/boot.sh OUT_DIR ...)
set -euo pipefail
# shellcheck source-path=SCRIPTDIR source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"

vm_check_test "${1:?usage: tests/vm/can_loop.sh OUT_DIR}" can_loop \
  'installed=[^ ]+ install ok installed' \
  'selfsensed=/usr/bin/selfsensed' \
  'check_config=ok' \
  'state_armed="armed"' \
  'position_reached=yes' \
  'temperature_shown=yes .*' \
  'bad_data_counted=yes .*' \
  'error_frame_counted=yes .*' \
  'state_after_injection="armed"' \
  'bus_off_counted=yes' \
  'bus_off_recovered=yes' \
  'state_after_bus_off="faulted"' \
  'state_rearmed="armed"' \
  'sim_device_exit=0' \
  'sim_device_summary=yes' \
  'timeouts_counted=yes .*' \
  'state_after_kill="faulted"' \
  'fault=driver_timeout' \
  'temp_timeouts_counted=yes .*' \
  'command_after_kill=0(\.0)?' \
  'daemon_exit=0' \
  'candump_frames=yes .*' \
  'candump_injected=3' \
  'last_command=18FF0001#00000000' \
  'realtime_allocations=0 locks=0 reads_ok=[0-9]+ writes_ok=2000 cycles=2000' \
  'fd_inputs_decoded=yes .*' \
  'fd_frames=yes .*'
