#!/usr/bin/env bash
# selfsensed end to end on the simulated transducer, paced in real time: the main job
# (scripts/main_job.sh: position staircase and sine, force steps, through `selfsense ctl`; the
# damping run; the self-heating run with and without adaptation), then
# its figures, the recordings read back by the tool, a bad configuration refused with its
# problems named, a reload, and SIGTERM to exit status 0. The main job watches the loop's state
# (scripts/daemon_runs.sh): a run that faults (a pause of several ms of a shared machine) is
# reported and done again once, and only a second fault fails the job and this test.
#   daemon_end_to_end.sh BUILD_DIR
set -euo pipefail
build=${1:?usage: daemon_end_to_end.sh BUILD_DIR}
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

bash "$root/scripts/main_job.sh" "$build" "$out" | tee "$out/main_job.out"
if [ -s "$out/faults.txt" ]; then
  echo "note: faulted runs, done again:"
  cat "$out/faults.txt"
fi
[ "$(grep -c 'selfsensed exited with status 0' "$out/main_job.out")" = 4 ] ||
  fail "a selfsensed did not exit 0 on SIGTERM: $(grep 'exited with status' "$out/main_job.out")"
# Figures: the loop holds the self-sensed signal on the setpoint; the true one is off by the
# model's error. Measured in ten runs (2026-11-26): S_hat 0.178-0.186 %, true S 0.210-0.219 %;
# T_hat 0.335-0.340 %, true T 0.966-1.119 %. The simulated plant advances one cycle per read, so
# only the setpoints' timing on the real clock varies from run to run (spread 4 % on S, 16 % on
# true T); each figure is asserted at about 1.3x the largest seen, under the daemon issue's goals
# (0.5 % and 2 %).
check() {  # check SEGMENT COLUMN LIMIT_PERCENT
  local v
  v=$(sed -n "s/^$1: .* $2 \([0-9.]*\) % RMS.*/\1/p" "$out/figures.txt")
  [ -n "$v" ] || fail "no $2 figure for $1 in: $(cat "$out/figures.txt")"
  awk -v v="$v" -v lim="$3" 'BEGIN { exit !(v < lim) }' || fail "$1 $2 $v % >= $3 %"
  echo "ok: $1 $2 $v % < $3 %"
}
check position S_hat 0.25
check position S 0.29
check force T_hat 0.44
check force T 1.45
# The damping run (config/damping-sim.yaml, a 300 Hz mount with 1 % damping, `ctl impulse`):
# measured 156.8-158.4 ms -> 9.9-11.1 ms on true S, 14.3-15.8x (14.3x in all ten runs of
# 2026-11-26); the issue's goal is 10x. Asserted: the ratio > 11x and the undamped ring-down
# > 120 ms (1.3x under the lowest seen), the damped one > 0 (a ring-down, not an impulse that
# never arrived).
ratio=$(sed -n 's/^damping: ring-down shortened \([0-9.]*\)x on true S.*/\1/p' "$out/figures.txt")
[ -n "$ratio" ] || fail "no damping figure in: $(cat "$out/figures.txt")"
awk -v r="$ratio" 'BEGIN { exit !(r > 11) }' || fail "damping shortened the ring-down only ${ratio}x"
echo "ok: damping ${ratio}x > 11x"
undamped=$(sed -n 's/^undamped: .* true S \([0-9.]*\) ms.*/\1/p' "$out/figures.txt")
awk -v v="$undamped" 'BEGIN { exit !(v > 120) }' || fail "the undamped mount rang only $undamped ms"
damped=$(sed -n 's/^damped: .* true S \([0-9.]*\) ms.*/\1/p' "$out/figures.txt")
awk -v v="$damped" 'BEGIN { exit !(v > 0) }' || fail "no damped ring-down: '$damped' ms"
echo "ok: ring-down of true S ${undamped} ms > 120 ms undamped, ${damped} ms > 0 damped"

# The self-heating run (config/heating-sim.yaml: a 200 Hz sine in open loop warms the stack,
# then position steps; docs/daemon.md, "Self-heating in the main job"). Measured in six runs
# (2026-11-27, with the thermal model carrying the estimate through the steps' holds): the stack
# warmed by 19.3-19.6 K; true S on the steps 0.245-0.268 % with adaptation (the issue's goal:
# 0.5 %; 0.691-0.784 % without the thermal model), 3.888-4.033 % without adaptation.
# Asserted: the warming at least the issue's 15 K, the adapted figure under 1.3x the largest
# seen (0.35 %), the unadapted one above the smallest / 1.3 (2.99 %: the warming is there to be
# corrected).
check heating-adapted S 0.35
rise=$(sed -n 's/^self-heating: the sine warmed the stack by \([0-9.]*\) K.*/\1/p' "$out/figures.txt")
[ -n "$rise" ] || fail "no self-heating figure in: $(cat "$out/figures.txt")"
awk -v v="$rise" 'BEGIN { exit !(v >= 15) }' || fail "the sine warmed the stack by only $rise K"
plain=$(sed -n 's/^heating-plain: .* true S \([0-9.]*\) % RMS.*/\1/p' "$out/figures.txt")
awk -v v="$plain" 'BEGIN { exit !(v > 2.99) }' || fail "without adaptation true S is only '$plain' %"
grep -q '^heating-adapted: .* equivalent 25.0 -> [0-9]' "$out/figures.txt" ||
  fail "no equivalent temperature in the adapted run: $(grep '^heating-adapted' "$out/figures.txt")"
echo "ok: self-heating by $rise K >= 15 K; true S without adaptation $plain % > 2.99 %"
grep -q 'plant (true)' "$out/main_job.html" && grep -q 'equivalent (adaptation)' "$out/main_job.html" ||
  fail "the page has no temperature plot"

# The recordings are contract CSV: the tool reads them (reconstruct from E and D).
for segment in position force undamped damped heating-adapted; do
  rec=$(cat "$out/$segment.path")
  "$build/src/cli/selfsense" reconstruct --model "$root/config/models/sim.yaml" --recording "$rec" \
    --out "$out/$segment.reconstructed.csv" >/dev/null || fail "$rec is not a readable recording"
done
grep -q '"state"' "$out/status.json" || fail "status has no state"
grep -q '"recording"' "$out/status.json" || fail "status has no recording"
[ -s "$out/main_job.html" ] && grep -q '<svg' "$out/main_job.html" || fail "no plots in the page"

# A bad configuration: non-zero exit, every problem named with file and line. The changed copies
# are written into the scratch directory beside links to config/models and config/plant.
# shellcheck source=tests/support/scratch_config.sh
source "$root/tests/support/scratch_config.sh"
link_shipped_config_dirs "$root" "$out"
bad=$out/.e2e-bad.yaml
sed -e 's/rate_hz: 10000/rate_hz: 3000/' -e 's/priority: 80/priority: 200/' "$root/config/sim.yaml" >"$bad"
if "$build/src/selfsensed/selfsensed" --config "$bad" 2>"$out/bad.err"; then
  fail "selfsensed started with a bad configuration"
fi
grep -q '.e2e-bad.yaml:[0-9]*: loop.priority: 200 must be within' "$out/bad.err" || fail "priority not named: $(cat "$out/bad.err")"
grep -q 'control.filters\[0\].frequency_hz' "$out/bad.err" || fail "notch not named: $(cat "$out/bad.err")"
# Reload: the gains through `ctl reload` and SIGHUP; a key that cannot change while running is
# refused by name and the daemon keeps running; SIGTERM still ends it with status 0.
cfg=$out/.e2e-reload.yaml
sed -e "s|path: ../build/sim/control.sock|path: $out/reload.sock|" \
  -e "s|directory: ../build/sim/recordings|directory: $out/reload-rec|" \
  -e "s|prometheus_file: ../build/sim/selfsensed.prom|prometheus_file: $out/reload.prom|" \
  "$root/config/sim.yaml" >"$cfg"
"$build/src/selfsensed/selfsensed" --config "$cfg" >"$out/reload.log" 2>&1 &
pid=$!
for _ in $(seq 100); do [ -S "$out/reload.sock" ] && break; sleep 0.1; done
ctl() { "$build/src/cli/selfsense" ctl --socket "$out/reload.sock" "$@"; }
sed -i 's/kp: 2.0e8/kp: 1.0e8/' "$cfg"
ctl reload | grep -q '"reloaded":"gains, filters, limits"' || fail "a gain change was not reloaded"
sed -i "s/rate_hz: 10000/rate_hz: 20000/" "$cfg"
if reply=$(ctl reload); then fail "a rate change was accepted: $reply"; fi
grep -q 'loop.rate_hz: cannot change while running' <<<"$reply" || fail "refusal does not name the key: $reply"
kill -HUP "$pid"
for _ in $(seq 50); do grep -q 'reload refused' "$out/reload.log" && break; sleep 0.1; done
grep -q 'reload refused: .*loop.rate_hz' "$out/reload.log" || fail "SIGHUP refusal not logged: $(cat "$out/reload.log")"
ctl status | grep -q '"state"' || fail "the daemon stopped answering after the refused reload"
kill -TERM "$pid"
rc=0
wait "$pid" || rc=$?
[ "$rc" -eq 0 ] || fail "selfsensed exited with $rc after SIGTERM"
echo "ok: reload of the gains, refusal naming loop.rate_hz, SIGTERM exit 0"
echo "daemon end to end: ok"
