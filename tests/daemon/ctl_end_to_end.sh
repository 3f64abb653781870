#!/usr/bin/env bash
# `selfsense ctl` end to end against a stand-in daemon (control_test_server) that replies with
# the request it understood: every request kind, the exit statuses (0 ok, 1 error reply, 2 no
# daemon) and the messages a user meets. Usage: ctl_end_to_end.sh SELFSENSE TEST_SERVER
set -euo pipefail
bin=$1
server=$2
work=$(mktemp -d)
sock=$work/control.sock
server_pid=
cleanup() {
  if [ -n "$server_pid" ]; then
    kill "$server_pid" 2>/dev/null || true
    wait "$server_pid" 2>/dev/null || true
  fi
  rm -rf "$work"
}
trap cleanup EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

"$server" "$sock" >"$work/server.out" 2>&1 &
server_pid=$!
for _ in $(seq 100); do
  grep -q ready "$work/server.out" 2>/dev/null && break
  sleep 0.05
done
[ -S "$sock" ] || fail "the test server did not create $sock: $(cat "$work/server.out")"

# expect STATUS EXPECTED_STDOUT ARGS...: runs `selfsense ctl --socket $sock ARGS`.
expect() {
  local want_status=$1 want_out=$2
  shift 2
  local status=0
  "$bin" ctl --socket "$sock" "$@" >"$work/out" 2>"$work/err" || status=$?
  [ "$status" -eq "$want_status" ] || fail "ctl $*: exit $status, expected $want_status ($(cat "$work/out" "$work/err"))"
  [ "$(cat "$work/out")" = "$want_out" ] || fail "ctl $*: printed '$(cat "$work/out")', expected '$want_out'"
  echo "ok: ctl $* -> $want_status"
}

for request in status arm disarm reset reload; do
  expect 0 "{\"ok\":true,\"request\":{\"request\":\"$request\"}}" "$request"
done
expect 0 '{"ok":true,"request":{"request":"setpoint","value":0.0005}}' setpoint 5e-4
expect 0 '{"ok":true,"request":{"request":"setpoint","value":-0.0001}}' setpoint -1e-4
expect 1 '{"error":"setpoint.value: 0.02 is outside [-0.0001, 0.0015] for position","ok":false}' setpoint 0.02
# The setpoint's unit follows the mode: a stress in force mode.
expect 0 '{"ok":true,"request":{"name":"force","request":"mode"}}' mode force
expect 0 '{"ok":true,"request":{"request":"setpoint","value":-1000000.0}}' setpoint -1e6
expect 1 '{"error":"mode.name: \"fast\" is not a mode (position, force, open-loop, damping)","ok":false}' mode fast
expect 0 '{"ok":true,"request":{"name":"position","request":"mode"}}' mode position
expect 0 '{"ok":true,"request":{"action":"start","request":"record"}}' record start
expect 0 '{"ok":true,"request":{"action":"stop","request":"record"}}' record stop
for action in freeze resume show; do
  expect 0 "{\"ok\":true,\"request\":{\"action\":\"$action\",\"request\":\"adapt\"}}" adapt "$action"
done

expect 0 '{"ok":true,"request":{"amplitude":0.0004,"frequency_hz":1.0,"offset":0.0006,"phase":0.0,"repeat":3,"request":"wave","shape":"sine"}}' \
  wave sine --amplitude 4e-4 --offset 6e-4 --frequency 1 --repeat 3
expect 0 '{"ok":true,"request":{"amplitude":1.0,"dwell_s":0.5,"frequency_hz":0.0,"levels":[0.0,0.0002,0.0004],"offset":0.0,"phase":0.0,"repeat":0,"request":"wave","shape":"staircase"}}' \
  wave staircase --levels 0,2e-4,4e-4 --dwell 0.5
expect 1 '{"error":"wave.amplitude: missing","ok":false}' wave triangle --frequency 2
expect 1 '{"error":"wave.levels: unknown member (wave shape sine takes: shape, amplitude, offset, frequency_hz, phase, repeat)","ok":false}' \
  wave sine --amplitude 1e-4 --frequency 1 --levels 1
expect 0 '{"ok":true,"request":{"request":"wave","shape":"stop"}}' wave stop

# Tables: one value per line (comments and blank lines skipped), or a CSV with a value column.
printf '# a ramp\n0\n1e-4\n\n3e-4\n' >"$work/ramp.txt"
expect 0 '{"ok":true,"request":{"amplitude":1.0,"dt_s":0.01,"frequency_hz":0.0,"offset":0.0,"phase":0.0,"repeat":0,"request":"wave","shape":"table","values":[0.0,0.0001,0.0003]}}' \
  wave table --table "$work/ramp.txt" --dt 0.01
printf 't,value\r\n0,2e-4\r\n0.1,1e-4\r\n' >"$work/ramp.csv"
expect 0 '{"ok":true,"request":{"amplitude":1.0,"dt_s":0.1,"frequency_hz":0.0,"offset":0.0,"phase":0.0,"repeat":0,"request":"wave","shape":"table","values":[0.0002,0.0001]}}' \
  wave table --table "$work/ramp.csv" --dt 0.1
printf '0\n1e-4\nabc\n' >"$work/bad.txt"
expect 1 '' wave table --table "$work/bad.txt" --dt 0.01
grep -qx "selfsense ctl: $work/bad.txt:3: 'abc' is not a number" "$work/err" || fail "bad table: $(cat "$work/err")"
printf 't,x\n0,1\n' >"$work/nocol.csv"
expect 1 '' wave table --table "$work/nocol.csv" --dt 0.01
grep -qx "selfsense ctl: $work/nocol.csv:1: no 'value' column (columns: t, x)" "$work/err" || fail "no value column: $(cat "$work/err")"
expect 1 '' wave staircase --levels 0,x --dwell 1
grep -qx "selfsense ctl: --levels: 'x' is not a number" "$work/err" || fail "bad levels: $(cat "$work/err")"

# --pretty indents; the options of ctl may also follow the request.
"$bin" ctl status --socket "$sock" --pretty >"$work/out"
grep -qx '  "ok": true,' "$work/out" || fail "--pretty: $(cat "$work/out")"
echo "ok: ctl status --socket ... --pretty"

# Usage errors are refused before anything is sent.
if "$bin" ctl --socket "$sock" record pause >/dev/null 2>&1; then fail "record pause was accepted"; fi
if "$bin" ctl --socket "$sock" adapt thaw >/dev/null 2>&1; then fail "adapt thaw was accepted"; fi
if "$bin" ctl --socket "$sock" setpoint >/dev/null 2>&1; then fail "setpoint without a value was accepted"; fi
echo "ok: usage errors"

# No daemon: exit 2 and the cause.
status=0
"$bin" ctl --socket "$work/none.sock" status >"$work/out" 2>"$work/err" || status=$?
[ "$status" -eq 2 ] || fail "no daemon: exit $status"
grep -qx "selfsense ctl: cannot connect to $work/none.sock: No such file or directory" "$work/err" ||
  fail "no daemon: $(cat "$work/err")"
[ ! -s "$work/out" ] || fail "no daemon: printed $(cat "$work/out")"
echo "ok: no daemon -> 2"

# The server removes its socket when it stops.
kill -TERM "$server_pid"
wait "$server_pid" || fail "the test server exited with $?"
server_pid=
[ ! -e "$sock" ] || fail "socket file left after stop"
echo "ctl end to end: ok"
