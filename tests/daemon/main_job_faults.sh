#!/usr/bin/env bash
# The main job's fault path, with faults injected rather than hoped for:
# 1. A run (scripts/daemon_runs.sh's watched_run, as the main job runs it) into which
#    `ctl impulse 10000 --duration 0.02` drives a fault once (10 kN for 20 ms on the stack: E and
#    D leave the model's range): the fault is reported with its name, cycle, time and cause, the
#    run is done again from the reset, and the repeat's figure counts armed samples only. The
#    cycle reported is the recording's first faulted row; the faulted recording gets no figure
#    from scripts/main_job_report.sh (exit 1).
# 2. The whole main job (scripts/main_job.sh) on a bench whose plant raises the amplifier's
#    fault line every 0.5 s (config/plant faults): the position run faults, is done again,
#    faults again: exit 1, both faults reported (amplifier_fault, cycle, time, cause), no figure.
#   main_job_faults.sh BUILD_DIR
set -euo pipefail
build=${1:?usage: main_job_faults.sh BUILD_DIR}
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
cli=$build/src/cli/selfsense
export SELFSENSE_CLI=$cli  # scripts/main_job_report.sh writes the page with it
out=$(mktemp -d)
pid=
cleanup() {
  [ -z "$pid" ] || kill -KILL "$pid" 2>/dev/null || true
  rm -rf "$out"
}
trap cleanup EXIT
fail() {
  echo "FAIL: $*" >&2
  exit 1
}
expect() {  # expect FILE EXTENDED_REGEX WHAT
  grep -Eq -- "$2" "$1" || fail "$3: no line matching '$2' in: $(cat "$1")"
}

# config/sim.yaml with absolute model and plant paths (PLANT), anywhere.
with_plant() {  # with_plant PLANT
  sed -e "s|model: models/sim.yaml|model: $root/config/models/sim.yaml|" \
    -e "s|plant: plant/daemon.yaml|plant: $1|" "$root/config/sim.yaml"
}

echo "== 1. a fault driven into a run once: reported, the run done again"
mkdir -p "$out/run"
with_plant "$root/config/plant/daemon.yaml" |
  sed -e "s|directory: ../build/sim/recordings|directory: $out/run/recordings|" \
    -e "s|path: ../build/sim/control.sock|path: $out/run/control.sock|" \
    -e "s|prometheus_file: ../build/sim/selfsensed.prom|prometheus_file: $out/run/selfsensed.prom|" \
    >"$out/run/sim.yaml"
"$build/src/selfsensed/selfsensed" --config "$out/run/sim.yaml" >"$out/run/daemon.log" 2>&1 &
pid=$!
for _ in $(seq 100); do [ -S "$out/run/control.sock" ] && break; sleep 0.1; done
rc=0
(
  ctl() { "$cli" ctl --socket "$out/run/control.sock" "$@"; }
  run_dir=$out/run
  # shellcheck source=scripts/daemon_runs.sh
  source "$root/scripts/daemon_runs.sh"
  steps() {
    record_start "$1"
    ctl setpoint 6.0e-4 >/dev/null
    hold 1.0
    if [ ! -e "$run_dir/injected" ]; then
      touch "$run_dir/injected"
      ctl impulse 10000 --duration 0.02 >/dev/null
    fi
    ctl setpoint 8.0e-4 >/dev/null
    hold 1.0
  }
  watched_run position position steps
) >"$out/run/out.txt" 2>&1 || rc=$?
cat "$out/run/out.txt"
kill -TERM "$pid"
wait "$pid" || fail "selfsensed exited with $? after SIGTERM"
pid=
[ "$rc" = 0 ] || fail "watched_run exited with $rc although the fault came once"
# name, cycle, time and cause: E and D out of the model's range (and T_hat out of its range)
expect "$out/run/out.txt" \
  "^FAULT: position: run 1 of 2: input_out_of_range at cycle [0-9]+ \(t = [0-9.]+ s\): E or D outside the model's range" \
  "the fault is not reported with its name, cycle, time and cause"
expect "$out/run/out.txt" "^position: repeating the run once" "the run was not repeated"
expect "$out/run/out.txt" "^position: run 2 of 2 clean" "the repeated run did not come out clean"
expect "$out/run/faults.txt" "^FAULT: position: run 1 of 2: " "the fault is not in faults.txt"
# The cycle and time reported are the recording's first faulted row.
faulted=$(sed -n 's/^FAULT: .*; recording: \(.*\)$/\1/p' "$out/run/faults.txt")
[ -f "$faulted" ] || fail "no faulted recording named: $(cat "$out/run/faults.txt")"
cycle=$(sed -n 's/^FAULT: .* input_out_of_range at cycle \([0-9]*\) (t = \([0-9.]*\) s).*/\1/p' "$out/run/faults.txt")
time=$(sed -n 's/^FAULT: .* input_out_of_range at cycle \([0-9]*\) (t = \([0-9.]*\) s).*/\2/p' "$out/run/faults.txt")
first=$(awk -F, '/^#/ { next } !h { for (i = 1; i <= NF; i++) c[$i] = i; h = 1; next }
  $c["state"] == 0 { printf "%d %.10g\n", $c["cycle"], $c["t"]; exit }' "$faulted")
[ "$first" = "$cycle $time" ] || fail "reported cycle $cycle at $time s, the recording's first faulted row: $first"
echo "ok: the fault reported at cycle $cycle, t = $time s: the recording's first faulted row"

# The repeat's figure counts armed samples only; the faulted recording gets none.
sleep 0.3  # the recorder's flush (the daemon stopped: done)
"$root/scripts/main_job_report.sh" "$out/run" position >"$out/run/report.txt" 2>&1 ||
  fail "no figure for the clean repeat: $(cat "$out/run/report.txt")"
expect "$out/run/report.txt" \
  "^position: [0-9]+ armed samples \([0-9]+ settled; 0 outside the armed state excluded\), .* S_hat [0-9.]+ % RMS" \
  "the clean repeat's figure"
echo "ok: $(grep '^position:' "$out/run/report.txt")"
echo "$faulted" >"$out/run/position.path"
if "$root/scripts/main_job_report.sh" "$out/run" position >"$out/run/report.txt" 2>&1; then
  fail "the report took a faulted recording: $(cat "$out/run/report.txt")"
fi
expect "$out/run/report.txt" \
  "^position: no figure: the loop faulted at t = $time s \(cycle $cycle: input_out_of_range.*\); [0-9]+ of [0-9]+ samples outside the armed state" \
  "the faulted recording's report"
! grep -q '% RMS' "$out/run/report.txt" || fail "a figure over a faulted recording: $(cat "$out/run/report.txt")"
echo "ok: $(grep '^position:' "$out/run/report.txt")"

echo "== 2. the main job on a bench whose amplifier faults every 0.5 s"
mkdir -p "$out/job"
plant=$out/job/faulting-plant.yaml
{
  sed '/^excitation:/,$d' "$root/config/plant/daemon.yaml"
  echo "  faults:"
  for k in $(seq 0 63); do
    awk -v k="$k" 'BEGIN { printf "    - {kind: amplifier_fault, channel: both, start_s: %.2f, duration_s: 0.001}\n", 0.5 + 0.5 * k }'
  done
  sed -n '/^excitation:/,$p' "$root/config/plant/daemon.yaml"
} >"$plant"
with_plant "$plant" >"$out/job/faulting-sim.yaml"  # the main job puts its files in its OUT_DIR
rc=0
SELFSENSE_MAIN_JOB_CONFIG=$out/job/faulting-sim.yaml bash "$root/scripts/main_job.sh" "$build" "$out/job/out" \
  >"$out/job/out.txt" 2>&1 || rc=$?
cat "$out/job/out.txt"
[ "$rc" = 1 ] || fail "the main job exited with $rc, not 1, on a fault that came back"
for run in 1 2; do
  expect "$out/job/out.txt" \
    "^FAULT: position: run $run of 2: amplifier_fault at cycle [0-9]+ \(t = [0-9.]+ s\): the amplifier's fault line" \
    "run $run's fault"
done
expect "$out/job/out.txt" "^position: repeating the run once" "the run was not repeated"
expect "$out/job/out.txt" "^FAILED: position faulted in its repeated run too; no figures: amplifier_fault" \
  "the job's end"
! grep -q '% RMS\|ring-down' "$out/job/out.txt" || fail "a figure printed for a faulted job"
[ ! -e "$out/job/out/figures.txt" ] || fail "figures written for a faulted job: $(cat "$out/job/out/figures.txt")"
! grep -q '^== force' "$out/job/out.txt" || fail "the job went on after the second fault"
grep -q 'stopped at cycle' "$out/job/out/daemon.log" || fail "the job's daemon was not stopped"
echo "ok: the main job on a faulting bench: two faults reported, exit 1, no figure"
echo "main job faults: ok"
