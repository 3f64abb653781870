#!/usr/bin/env bash
# The README's main job over Modbus TCP: `selfsense sim-device` serves the simulated transducer
# on 127.0.0.1:1502 (config/modbus-sim.yaml's port), and scripts/main_job.sh runs the daemon on
# config/modbus-sim.yaml against it (position staircase and sine, force steps, figures, plots).
#   scripts/modbus_main_job.sh BUILD_DIR OUT_DIR
set -euo pipefail
build=${1:?usage: scripts/modbus_main_job.sh BUILD_DIR OUT_DIR}
out=${2:?usage: scripts/modbus_main_job.sh BUILD_DIR OUT_DIR}
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
mkdir -p "$out"
"$build/src/cli/selfsense" sim-device --modbus-tcp 127.0.0.1:1502 --rate 1000 --priority 60 \
  --plant "$root/config/plant/daemon.yaml" >"$out/sim_device.log" 2>&1 &
device=$!
trap 'kill -TERM "$device" 2>/dev/null || true' EXIT
for _ in $(seq 100); do grep -qs 'modbus-tcp on' "$out/sim_device.log" && break; sleep 0.05; done
grep -q 'modbus-tcp on' "$out/sim_device.log" || { cat "$out/sim_device.log" >&2; exit 1; }
SELFSENSE_MAIN_JOB_CONFIG=$root/config/modbus-sim.yaml bash "$root/scripts/main_job.sh" "$build" "$out"
kill -TERM "$device"
wait "$device"
echo "sim-device exited with status $?"
