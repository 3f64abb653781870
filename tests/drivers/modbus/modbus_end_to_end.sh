#!/usr/bin/env bash
# selfsensed end to end over Modbus TCP: `selfsense sim-device` serves the simulated transducer
# on a free loopback port, the daemon runs config/modbus-sim.yaml against it (paced in real time),
# is armed in position mode through `selfsense ctl` and follows a setpoint staircase; the
# tracking error of S_hat and of the plant's true S comes from the daemon's own recording
# (scripts/main_job_report.sh, as in the main job). The run watches the loop's state as the
# main job's do (scripts/daemon_runs.sh): a run that faults (a late wake-up on a shared machine
# can make the sample stale) is reported and done again once; a second fault fails the test.
# A staircase whose true S misses its limit after the loop missed a reversal of E (the device's
# clock and the loop's, unseen_reversals below) is reported and run once more; a miss without
# one, or a second miss, fails. Then the device is killed: the loop faults
# (driver_timeout) and counts the errors; the device restarts on the same port: the driver
# reconnects and the loop can be reset and armed again. SIGTERM ends both with status 0.
#   modbus_end_to_end.sh BUILD_DIR
set -euo pipefail
build=${1:?usage: modbus_end_to_end.sh BUILD_DIR}
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)
cli=$build/src/cli/selfsense
export SELFSENSE_CLI=$cli  # scripts/main_job_report.sh writes the page with it
out=$(mktemp -d)
# The changed copy of config/modbus-sim.yaml lives in the scratch directory, beside links to
# config/models and config/plant (its paths are relative to its file).
config=$out/modbus-sim.yaml
# shellcheck source=tests/support/scratch_config.sh
source "$root/tests/support/scratch_config.sh"
link_shipped_config_dirs "$root" "$out"
device_pid= daemon_pid=
cleanup() {
  [ -n "$daemon_pid" ] && kill -KILL "$daemon_pid" 2>/dev/null || true
  [ -n "$device_pid" ] && kill -KILL "$device_pid" 2>/dev/null || true
  rm -rf "$out"
}
trap cleanup EXIT
fail() { echo "FAIL: $*" >&2; [ -f "$out/daemon.log" ] && tail -20 "$out/daemon.log" >&2; exit 1; }

start_device() {  # start_device PORT (0: a free one)
  "$cli" sim-device --modbus-tcp "127.0.0.1:$1" --plant "$root/config/plant/daemon.yaml" \
    --rate 1000 --priority 60 >"$out/device.log" 2>&1 &
  device_pid=$!
  for _ in $(seq 100); do grep -qs 'modbus-tcp on' "$out/device.log" && break; sleep 0.05; done
  port=$(sed -n 's/.*modbus-tcp on 127.0.0.1:\([0-9]*\),.*/\1/p' "$out/device.log")
  [ -n "$port" ] || fail "sim-device did not start: $(cat "$out/device.log")"
}
start_device 0
# CI runs other real-time tests on the same cores: a late wake-up makes the loop catch up with a
# burst of cycles that finds no new samples, so the staleness allowance is wider than shipped.
sed -e "s|port: 1502|port: $port|" \
  -e "s|max_age_s: 0.005 |max_age_s: 0.05 |" -e "s|sample_timeout_s: 0.05 |sample_timeout_s: 0.1 |" \
  -e "s|directory: ../build/modbus-sim/recordings|directory: $out/recordings|" \
  -e "s|path: ../build/modbus-sim/control.sock|path: $out/control.sock|" \
  -e "s|prometheus_file: ../build/modbus-sim/selfsensed.prom|prometheus_file: $out/selfsensed.prom|" \
  "$root/config/modbus-sim.yaml" >"$config"
"$cli" check-config "$config" || fail "check-config refused the Modbus configuration"
"$build/src/selfsensed/selfsensed" --config "$config" >"$out/daemon.log" 2>&1 &
daemon_pid=$!
for _ in $(seq 100); do [ -S "$out/control.sock" ] && break; sleep 0.1; done
ctl() { "$cli" ctl --socket "$out/control.sock" "$@"; }
counter() { ctl status | sed -n "s/.*\"$1\":\([0-9]*\).*/\1/p"; }
run_dir=$out
# shellcheck source=scripts/daemon_runs.sh
source "$root/scripts/daemon_runs.sh"

staircase() {
  record_start "$1"
  local level
  for level in 3.0e-4 9.0e-4 6.0e-4; do
    ctl setpoint "$level" >/dev/null
    hold 1.0
  done
}
figure() {  # figure COLUMN: the position run's RMS figure of COLUMN in %
  sed -n "s/^position: .* $1 \([0-9.]*\) % RMS.*/\1/p" "$out/figures.txt"
}
check() {  # check COLUMN LIMIT_PERCENT
  local v
  v=$(figure "$1")
  [ -n "$v" ] || fail "no $1 figure in: $(cat "$out/figures.txt")"
  awk -v v="$v" -v lim="$2" 'BEGIN { exit !(v < lim) }' || fail "position $1 $v % >= $2 %"
  echo "ok: position over Modbus TCP: $1 $v % RMS < $2 %"
}
# unseen_reversals RECORDING: the reversals of the command (a local extreme at least 5e3 V/m
# beyond both neighbours) whose level the loop never read back as E in the next four cycles
# (within 2e3 V/m: ten times E's noise; the device's amplifier puts the command on E one device
# period later), one line each. The device and the loop run on free-running clocks of one rate:
# where their phases meet, a late poll reads one sample twice and misses the next. A missed
# level on a ramp costs nothing; a missed reversal leaves the model's hysteresis memory short of
# the plant's until a larger excursion wipes it out (traced in one run: true S 0.184 % RMS over
# the staircase with S_hat on the setpoint).
unseen_reversals() {
  awk -F, '
    /^#/ { next }
    !header { for (i = 1; i <= NF; i++) col[$i] = i; header = 1; next }
    $col["state"] != 2 { next }
    { n++; t[n] = $col["t"]; c[n] = $col["command"]; e[n] = $col["E"] }
    END {
      for (k = 2; k + 4 <= n; k++) {
        up = c[k] - c[k - 1] >= 5e3 && c[k] - c[k + 1] >= 5e3
        down = c[k - 1] - c[k] >= 5e3 && c[k + 1] - c[k] >= 5e3
        if (!up && !down) continue
        seen = 0
        for (j = k + 1; j <= k + 4; j++) if (e[j] - c[k] < 2e3 && c[k] - e[j] < 2e3) seen = 1
        if (!seen) printf "t = %s s: commanded %.0f V/m, not read back\n", t[k], c[k]
      }
    }' "$1"
}
# The staircase and its figures; a run whose true S misses the goal and in which the loop missed
# a reversal of E is reported and done again once (the clocks' phases differ from run to run).
# S_hat is held to its limit either way: it says whether the loop follows its own estimate.
sleep 0.5
for attempt in 1 2; do
  watched_run position position staircase
  sleep 0.3  # the recorder's flush
  "$root/scripts/main_job_report.sh" "$out" position
  unseen=$(unseen_reversals "$(cat "$out/position.path")")
  echo "reversals of E the loop did not read: $(grep -c . <<<"$unseen" || true)${unseen:+ ($unseen)}"
  s=$(figure S)
  if [ "$attempt" = 2 ] || [ -z "$unseen" ] || [ -z "$s" ] ||
    ! awk -v v="$s" 'BEGIN { exit !(v >= 0.5) }'; then
    break
  fi
  echo "REPEAT: true S $s % RMS with a reversal the loop did not read: the staircase once more"
done
# Measured in twelve runs (2026-11-26): S_hat 0.047-0.049 %, asserted at about 1.3x of that.
# True S 0.036-0.278 % (ten of them 0.043-0.083 %): the device's plant runs on its own clock in
# another process and its spread is wide, so the figure is measured-only and asserted at the
# daemon issue's goal (0.5 %), 1.8x the largest seen.
# Two CI runs measured 0.742 % and 0.790 % (S_hat 0.050 % and 0.048 %). Traced on 2026-12-06 in
# some 90 runs under load (one at 0.479 %, one at 0.184 %): in the 0.184 % run the loop read one
# sample twice and missed the one after, which held the peak of E's overshoot on the first step
# (commanded 944 727 V/m, read at most 932 881). Its hysteresis memory stayed short of the
# plant's, and S_hat sat 1.1 % of its level above true S until the step to 9e-4 wiped it out.
# Such a run is now done once more (unseen_reversals above). Seeing every sample of a polled
# device needs the device's clock to pace the loop, or a buffer of samples on the device; neither
# is built. (A descheduled device used to drop the periods it missed, which put its plant behind
# the wall clock; it now replays them, drivers/modbus_sim/modbus_sim_device.cpp.)
check S_hat 0.065
check S 0.5
# A clean run: no exception responses and no bad frames (a timeout or two may happen on a loaded
# machine; they are counted, and the figures above hold).
[ "$(counter driver_device_faults)" = 0 ] || fail "exception responses in a clean run: $(ctl status)"
[ "$(counter driver_bad_data)" -le "$(counter driver_timeouts)" ] || fail "bad frames in a clean run: $(ctl status)"
echo "ok: clean run: $(counter driver_errors) bus errors, $(counter driver_timeouts) timeouts, $(counter driver_stale) stale reads of $(counter driver_reads)"

# The device goes away: the loop faults, the driver counts; it comes back: reconnect and re-arm.
kill -KILL "$device_pid"
wait "$device_pid" 2>/dev/null || true
sleep 0.5
ctl status | grep -q '"driver_timeout"' || fail "no driver_timeout fault without the device: $(ctl status)"
[ "$(counter driver_errors)" -gt 0 ] || fail "the lost link was not counted: $(ctl status)"
if ctl reset >/dev/null 2>&1; then
  ctl status | grep -q '"state":"ready"' && fail "reset accepted while the device is gone"
fi
start_device "$port"
sleep 1.0
[ "$(counter driver_reconnects)" -ge 1 ] || fail "no reconnect counted: $(ctl status)"
# Re-armed as a user would: reset until ready, settle, arm (arm_run). A back-to-back reset and
# arm were once refused here under the sanitizers (one CI run; the reason was not printed then,
# most likely a fresh fault from the restarted device latched between the two). Like a watched
# run, a failed re-arm is now reported with its faults and tried once more; a second one fails.
rearmed=
for attempt in 1 2; do
  if arm_run position; then rearmed=yes; break; fi
  echo "FAULT: re-arming after the reconnect, try $attempt of 2: $(fault_report "$(daemon_status)")"
done
[ -n "$rearmed" ] || fail "not re-armed after the device came back: $(fault_report "$(daemon_status)")"
ctl setpoint 5.0e-4 >/dev/null
sleep 1.0
ctl status | grep -q '"state":"armed"' || fail "not armed after reconnecting: $(ctl status)"
echo "ok: device killed -> driver_timeout and $(counter driver_errors) bus errors; restarted -> $(counter driver_reconnects) reconnect(s), armed again"

kill -TERM "$daemon_pid"
rc=0
wait "$daemon_pid" || rc=$?
daemon_pid=
[ "$rc" -eq 0 ] || fail "selfsensed exited with $rc after SIGTERM"
kill -TERM "$device_pid"
rc=0
wait "$device_pid" || rc=$?
device_pid=
[ "$rc" -eq 0 ] || fail "sim-device exited with $rc after SIGTERM"
echo "modbus daemon end to end: ok"
