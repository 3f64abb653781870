#!/usr/bin/env bash
# The README's main job: selfsensed on config/sim.yaml (the simulated transducer, paced in real
# time), armed through `selfsense ctl`: a position staircase and sine, a force step, a damping
# run; for each, the tracking error of S_hat (or T_hat) and of the plant's true S (or T) against
# the setpoint, from the daemon's own recording; an HTML page with the plots; a clean stop.
#   scripts/main_job.sh BUILD_DIR OUT_DIR
set -euo pipefail
build=${1:?usage: scripts/main_job.sh BUILD_DIR OUT_DIR}
out=${2:?usage: scripts/main_job.sh BUILD_DIR OUT_DIR}
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cli=$build/src/cli/selfsense
daemon=$build/src/selfsensed/selfsensed
mkdir -p "$out"
out=$(cd "$out" && pwd)

# The shipped configuration with this run's paths (SELFSENSE_MAIN_JOB_CONFIG: another one of
# config/, e.g. config/modbus-sim.yaml through scripts/modbus_main_job.sh).
config=$root/config/.main-job.yaml
sed -e "s|directory: ../build/[a-z-]*/recordings|directory: $out/recordings|" \
  -e "s|path: ../build/[a-z-]*/control.sock|path: $out/control.sock|" \
  -e "s|prometheus_file: ../build/[a-z-]*/selfsensed.prom|prometheus_file: $out/selfsensed.prom|" \
  "${SELFSENSE_MAIN_JOB_CONFIG:-$root/config/sim.yaml}" >"$config"
"$cli" check-config "$config"

"$daemon" --config "$config" >"$out/daemon.log" 2>&1 &
pid=$!
cleanup() {
  kill -TERM "$pid" 2>/dev/null || true
  wait "$pid" 2>/dev/null || true
  rm -f "$config"
}
trap cleanup EXIT
for _ in $(seq 100); do
  [ -S "$out/control.sock" ] && break
  sleep 0.1
done
ctl() { "$cli" ctl --socket "$out/control.sock" "$@"; }
value() { sed -n "s/.*\"$1\":\([^,}]*\).*/\1/p"; }

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
kill -TERM "$pid"
wait "$pid"
status=$?
trap - EXIT
rm -f "$config"
echo "selfsensed exited with status $status"
"$root/scripts/main_job_report.sh" "$out" position force
