#!/usr/bin/env bash
# The README's main job: selfsensed on config/sim.yaml (the simulated transducer, paced in real
# time), armed through `selfsense ctl`: a position staircase and sine, a force step; then
# selfsensed on config/damping-sim.yaml (the same stack on a 300 Hz mount) for a damping run: a
# force impulse from the bench (`ctl impulse`) in open loop and again with positive position
# feedback on S_hat. For each, from the daemon's own recording, the tracking error of S_hat (or
# T_hat) and of the plant's true S (or T) against the setpoint, or the ring-down times; an HTML
# page with the plots; a clean stop of each daemon. Then the self-heating run on
# config/heating-sim.yaml (the stack warms with the power it takes): a 200 Hz sine in open loop
# warms it by more than 15 K, then position steps, once with the online adaptation and once on a
# fresh daemon without it; the figures of both beside each other and the plant's temperature
# against the adaptation's equivalent temperature on the page.
# Each run watches the daemon's state (scripts/daemon_runs.sh): a run in which the loop faults
# is reported (fault, cycle, time, cause; OUT_DIR/faults.txt) and done again once; a second
# fault ends the job with exit 1 and no figures. The figures count armed samples only
# (scripts/main_job_report.sh).
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
run_dir=$out
rm -f "$out/faults.txt"
# shellcheck source=scripts/daemon_runs.sh
source "$root/scripts/daemon_runs.sh"

config=$out/config/main-job.yaml
# shellcheck source=scripts/daemon_process.sh
source "$root/scripts/daemon_process.sh"

start_daemon "${SELFSENSE_MAIN_JOB_CONFIG:-$root/config/sim.yaml}"

# The runs (watched_run NAME MODE RUN: armed in MODE, RUN NAME records and holds).
position_run() {
  record_start "$1"
  local level
  for level in 1.5e-4 6.0e-4 1.05e-3 3.5e-4 8.0e-4; do
    ctl setpoint "$level" >/dev/null
    hold 0.8
  done
  ctl wave sine --amplitude 4.5e-4 --offset 6.0e-4 --frequency 1 --repeat 3 >/dev/null
  hold 3.2
}
force_run() {
  record_start "$1"
  local level
  for level in -5.0e6 -8.0e6 -6.0e6; do
    ctl setpoint "$level" >/dev/null
    hold 0.8
  done
}

echo "== position: staircase over 80 % of the stroke, then a 1 Hz sine"
watched_run position position position_run

echo "== force: steps of compressive stress"
watched_run force force force_run

ctl status --pretty >"$out/status.json"
stop_daemon
segments=(position force)

if [ -z "${SELFSENSE_MAIN_JOB_CONFIG:-}" ]; then
  echo "== damping: a 300 N impulse of 0.5 ms on a 300 Hz mount, in open loop, then with PPF on S_hat"
  start_daemon "$root/config/damping-sim.yaml"
  # Recorded from rest: armed, settled on the setpoint, then the impulse.
  damping_run() {
    ctl setpoint 6.0e-4 >/dev/null
    hold 0.6
    record_start "$1"
    hold 0.1
    ctl impulse 300 --duration 5e-4 >/dev/null
    hold 0.6
  }
  watched_run undamped open-loop damping_run
  watched_run damped damping damping_run
  stop_daemon
  segments+=(undamped damped)

  echo "== self-heating: a 200 Hz sine in open loop warms the stack, then position steps; with adaptation, then without"
  # Each on a fresh daemon: its plant starts at 25 degC (heating_run: scripts/daemon_runs.sh).
  start_daemon "$root/config/heating-sim.yaml"
  watched_run heating-adapted open-loop heating_run
  ctl status --pretty >"$out/status-heating.json"
  stop_daemon
  start_daemon "$root/config/heating-sim.yaml" \
    's|^  enabled: true \( *# true: the loop runs the adapted\)|  enabled: false\1|'
  watched_run heating-plain open-loop heating_run
  stop_daemon
  segments+=(heating-adapted heating-plain)
fi
trap - EXIT
SELFSENSE_CLI=$cli "$root/scripts/main_job_report.sh" "$out" "${segments[@]}"
