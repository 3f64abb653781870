# shellcheck shell=bash
# Runs of selfsensed in real time that watch the daemon's state: sourced (under
# `set -euo pipefail`) by scripts/main_job.sh, scripts/heating_feedforward.sh (both run
# heating_run, below) and by the tests that run the daemon in real time
# (tests/daemon/daemon_end_to_end.sh through the main job, tests/drivers/modbus/
# modbus_end_to_end.sh, tests/daemon/main_job_faults.sh). The caller defines `ctl` (selfsense ctl
# on its daemon's socket) and `run_dir` (where NAME.path and faults.txt are written).
#
#   watched_run NAME MODE BODY
# One run: disarm, mode MODE, reset (retried while a fault's cause still holds), arm, then BODY
# NAME in a subshell with errexit, which records with `record_start NAME` and waits with
# `hold SECONDS` (it polls the daemon's state and fails as soon as the loop leaves `armed`). The
# recording is stopped and the state read once more: a run is clean only if the loop stayed
# armed to the end. A faulted run is reported (stdout and run_dir/faults.txt) with each latched
# fault's name, cycle, time and cause (status `fault_details`) and the recording it spoiled, and
# is done again once from the reset; a second fault ends the caller with exit 1 and that report
# (its EXIT trap stops the daemon). A run that stops for another reason (a refused request, no
# daemon) ends the caller with exit 1 at once. NAME.path holds the clean run's recording.
: "${run_dir:?set run_dir before sourcing scripts/daemon_runs.sh}"

# The daemon's status on one line, or exit 1 when no daemon answers.
daemon_status() {
  local reply
  if ! reply=$(ctl status 2>&1); then
    echo "no daemon answers: $reply" >&2
    return 1
  fi
  printf '%s\n' "$reply"
}
# loop_state STATUS: armed, ready or faulted.
loop_state() {
  if [[ $1 =~ \"state\":\"([a-z]+)\" ]]; then printf '%s\n' "${BASH_REMATCH[1]}"; fi
}

# fault_report STATUS: one line naming each latched fault: name, cycle, time, cause.
fault_report() {
  local status=$1 names name detail cycle time cause report=''
  names=$(sed -n 's/.*"faults":\[\([^]]*\)\].*/\1/p' <<<"$status" | tr -d '"' | tr ',' ' ')
  for name in $names; do
    detail=$(grep -o "\"$name\":{[^}]*}" <<<"$status" | head -1)
    cycle=$(sed -n 's/.*"first_cycle":\([0-9-]*\).*/\1/p' <<<"$detail")
    time=$(sed -n 's/.*"first_s":\([0-9.e+-]*\).*/\1/p' <<<"$detail")
    cause=$(sed -n 's/.*"cause":"\([^"]*\)".*/\1/p' <<<"$detail")
    report+="${report:+; }$name at cycle $cycle (t = $time s): $cause"
    if [ "$name" = overrun ]; then
      report+=" [timing: $(sed -n 's/.*"overruns":\([0-9]*\).*/\1/p' <<<"$status") deadlines missed since the start, wake-up latency max $(sed -n 's/.*"wake_latency_ns":{"max":\([0-9]*\).*/\1/p' <<<"$status" | awk '{ printf "%.2f", $1 / 1e6 }') ms]"
    fi
  done
  [ -n "$report" ] || report="the loop left the armed state ($(loop_state "$status")) with no fault latched"
  printf '%s\n' "$report"
}

# hold SECONDS: waits, reading the state every 0.2 s; fails when the loop is not armed. (Bash
# arithmetic in microseconds: a process start costs tens of ms on a loaded machine.)
hold() {
  local int=${1%%.*} frac='' now end left nap status
  [[ $1 != *.* ]] || frac=${1#*.}
  frac=${frac}000000
  now=${EPOCHREALTIME/[.,]/}
  end=$((now + 10#$int * 1000000 + 10#${frac:0:6}))
  while :; do
    now=${EPOCHREALTIME/[.,]/}
    left=$((end - now))
    ((left > 0)) || return 0
    ((left < 200000)) || left=200000
    printf -v nap '%d.%06d' $((left / 1000000)) $((left % 1000000))
    sleep "$nap"
    status=$(daemon_status) || return 1
    [[ $status =~ \"state\":\"armed\" ]] || return 1
  done
}

# record_start NAME: starts the recorder, its file's path in run_dir/NAME.path.
record_start() {
  local reply
  reply=$(ctl record start)
  sed -n 's/.*"path":"\([^"]*\)".*/\1/p' <<<"$reply" >"$run_dir/$1.path"
}

# arm_run MODE: disarmed, mode set, reset until ready (a fault's cause may hold a moment, up to
# 5 s), settled, armed. Fails when the loop stays faulted or faults while settling.
arm_run() {
  local i
  ctl disarm >/dev/null 2>&1 || true
  ctl mode "$1" >/dev/null
  for i in $(seq 50); do
    ctl reset >/dev/null 2>&1 || true
    [ "$(loop_state "$(daemon_status)")" = ready ] && break
    [ "$i" -lt 50 ] || return 1
    sleep 0.1
  done
  sleep 0.3
  ctl arm >/dev/null 2>&1
}

watched_run() {
  local name=$1 mode=$2 body=$3 attempt rc status report recording
  for attempt in 1 2; do
    rm -f "$run_dir/$name.path"
    rc=0
    set +e
    (
      set -e
      arm_run "$mode"
      "$body" "$name"
    )
    rc=$?
    set -e
    ctl record stop >/dev/null 2>&1 || true
    status=$(daemon_status) || exit 1
    if [ "$(loop_state "$status")" = armed ]; then
      ctl disarm >/dev/null 2>&1 || true  # (a fault after the stop: the next run resets)
      if [ "$rc" -ne 0 ]; then
        echo "FAILED: $name: the run stopped (status $rc) with the loop armed" >&2
        exit 1
      fi
      [ "$attempt" = 1 ] || echo "$name: run 2 of 2 clean" | tee -a "$run_dir/faults.txt"
      echo "$name: $(cat "$run_dir/$name.path")"
      return 0
    fi
    report=$(fault_report "$status")
    recording=$(cat "$run_dir/$name.path" 2>/dev/null || echo "none, faulted before recording")
    echo "FAULT: $name: run $attempt of 2: $report; recording: $recording" |
      tee -a "$run_dir/faults.txt"
    if [ "$attempt" = 2 ]; then
      echo "FAILED: $name faulted in its repeated run too; no figures: $report" >&2
      exit 1
    fi
    echo "$name: repeating the run once (reset, re-arm, the whole run again)"
  done
}

# heating_run NAME: the main job's self-heating run (config/heating-sim.yaml; watched_run's
# BODY, mode open-loop). A 200 Hz sine in open loop (3000 periods, 15 s of the loop's clock,
# which a late cycle stretches) starts and ends at its offset; once it has ended, the position
# mode holds there and a table plays the position run's staircase with edges of 3 ms (written
# to run_dir/heating-steps.txt). (The heating configuration's shaper lets the setpoint move 1.0
# per s, which the sine needs; a setpoint step at that slew takes 0.5 ms, one period of the
# mount's 2 kHz resonance, which rings it. The edges of 3 ms come near the position run's, 9 ms
# at 0.05 per s; each still moves the setpoint by more than 1 % of its range per sample, so the
# figures take it for a step.)
heating_run() {
  awk 'BEGIN {
    n = split("6.0e-4 1.5e-4 6.0e-4 1.05e-3 3.5e-4 8.0e-4", level, " ")
    for (i = 1; i <= n; i++) for (k = 0; k < (i == 1 ? 67 : 267); k++) print level[i]
  }' >"$run_dir/heating-steps.txt"
  record_start "$1"
  ctl wave sine --amplitude 4.5e-4 --offset 6.0e-4 --frequency 200 --repeat 3000 >/dev/null
  hold 15
  while [[ $(daemon_status) =~ \"wave_running\":true ]]; do hold 0.05; done
  ctl mode position >/dev/null
  ctl wave table --table "$run_dir/heating-steps.txt" --dt 0.003 --repeat 1 >/dev/null
  hold 4.3
}
