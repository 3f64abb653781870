#!/usr/bin/env bash
# The README's main job: selfsensed on config/sim.yaml (the simulated transducer, paced in real
# time), armed through `selfsense ctl`: a position staircase and sine, a force step; then
# selfsensed on config/damping-sim.yaml (the same stack on a 300 Hz mount) for a damping run: a
# force impulse from the bench (`ctl impulse`) in open loop and again with positive position
# feedback on S_hat. For each, from the daemon's own recording, the tracking error of S_hat (or
# T_hat) and of the plant's true S (or T) against the setpoint, or the ring-down times; an HTML
# page with the plots; a clean stop of each daemon.
#   scripts/main_job.sh BUILD_DIR OUT_DIR
# SELFSENSE_MAIN_JOB_CONFIG: another configuration of config/ for the first part (e.g.
# config/modbus-sim.yaml through scripts/modbus_main_job.sh), which then skips the damping run
# (it needs the simulated transducer's force input).
set -euo pipefail
build=${1:?usage: scripts/main_job.sh BUILD_DIR OUT_DIR}
out=${2:?usage: scripts/main_job.sh BUILD_DIR OUT_DIR}
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cli=$build/src/cli/selfsense
daemon=$build/src/selfsensed/selfsensed
mkdir -p "$out"
out=$(cd "$out" && pwd)

# start_daemon SHIPPED_CONFIG: the configuration with this run's paths (beside the shipped one,
# so its relative paths resolve), checked, and selfsensed started on it; waits for its socket.
config=$root/config/.main-job.yaml
pid=
start_daemon() {
  sed -e "s|directory: ../build/[a-z-]*/recordings|directory: $out/recordings|" \
    -e "s|path: ../build/[a-z-]*/control.sock|path: $out/control.sock|" \
    -e "s|prometheus_file: ../build/[a-z-]*/selfsensed.prom|prometheus_file: $out/selfsensed.prom|" \
    "$1" >"$config"
  "$cli" check-config "$config"
  rm -f "$out/control.sock"  # the previous daemon's
  "$daemon" --config "$config" >>"$out/daemon.log" 2>&1 &
  pid=$!
  for _ in $(seq 100); do
    [ -S "$out/control.sock" ] && break
    sleep 0.1
  done
}
# stop_daemon: SIGTERM, its exit status printed (the end-to-end test checks it).
stop_daemon() {
  kill -TERM "$pid"
  local status=0
  wait "$pid" || status=$?
  pid=
  rm -f "$config"
  echo "selfsensed exited with status $status"
}
cleanup() {
  [ -n "$pid" ] && kill -TERM "$pid" 2>/dev/null && wait "$pid" 2>/dev/null
  rm -f "$config"
}
trap cleanup EXIT
ctl() { "$cli" ctl --socket "$out/control.sock" "$@"; }
value() { sed -n "s/.*\"$1\":\([^,}]*\).*/\1/p"; }

start_daemon "${SELFSENSE_MAIN_JOB_CONFIG:-$root/config/sim.yaml}"

# segment NAME MODE: one recording per segment.
segment_start() {
  ctl disarm >/dev/null 2>&1 || true
  ctl mode "$2" >/dev/null
  ctl reset >/dev/null 2>&1 || true
  sleep 0.3
  ctl arm >/dev/null
  ctl record start | value path | tr -d '"' >"$out/$1.path"
}
segment_stop() {
  ctl record stop >/dev/null
  ctl disarm >/dev/null || true
  echo "$1: $(cat "$out/$1.path")"
}

echo "== position: staircase over 80 % of the stroke, then a 1 Hz sine"
segment_start position position
for level in 1.5e-4 6.0e-4 1.05e-3 3.5e-4 8.0e-4; do
  ctl setpoint "$level" >/dev/null
  sleep 0.8
done
ctl wave sine --amplitude 4.5e-4 --offset 6.0e-4 --frequency 1 --repeat 3 >/dev/null
sleep 3.2
segment_stop position

echo "== force: steps of compressive stress"
segment_start force force
for level in -5.0e6 -8.0e6 -6.0e6; do
  ctl setpoint "$level" >/dev/null
  sleep 0.8
done
segment_stop force

ctl status --pretty >"$out/status.json"
stop_daemon
segments=(position force)

if [ -z "${SELFSENSE_MAIN_JOB_CONFIG:-}" ]; then
  echo "== damping: a 300 N impulse of 0.5 ms on a 300 Hz mount, in open loop, then with PPF on S_hat"
  start_daemon "$root/config/damping-sim.yaml"
  for run in open-loop:undamped damping:damped; do
    # Recorded from rest: armed, settled on the setpoint, then the impulse.
    ctl disarm >/dev/null 2>&1 || true
    ctl mode "${run%%:*}" >/dev/null
    ctl reset >/dev/null 2>&1 || true
    sleep 0.3
    ctl arm >/dev/null
    ctl setpoint 6.0e-4 >/dev/null
    sleep 0.6
    ctl record start | value path | tr -d '"' >"$out/${run#*:}.path"
    sleep 0.1
    ctl impulse 300 --duration 5e-4 >/dev/null
    sleep 0.6
    segment_stop "${run#*:}"
  done
  stop_daemon
  segments+=(undamped damped)
fi
trap - EXIT
"$root/scripts/main_job_report.sh" "$out" "${segments[@]}"
