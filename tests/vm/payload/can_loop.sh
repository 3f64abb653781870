#!/usr/bin/env bash
# Inside the VM, with the kernel's SocketCAN stack: the daemon selfsensed with its CAN driver
# against `selfsense sim-device --can` (the simulated transducer as a CAN node) on a vcan
# interface, both as this build's selfsense package installs them with apt (lib/package.sh;
# /usr/bin, Debian's libraries), on its example /etc/selfsense/examples/can-sim.yaml and the
# plant under /usr/share/selfsense, run as plain processes beside can-utils. Checks that the loop, armed in position mode through
# `selfsense ctl`, brings S_hat to the setpoint; that the stack's temperature arrives in its own
# frame and reaches the status; that candump sees the input and command frames;
# that a short input frame and an error frame injected with cansend are counted (and do not
# stop the loop); that killing the node gives timeout faults and the safe output (E = 0 on the
# bus); then the same over CAN FD (MTU 72). Prints "name=value" lines that
# tests/vm/can_loop.sh checks; the figures (latency, loop rate) are printed, not asserted.
set -euo pipefail
# shellcheck source-path=SCRIPTDIR source=lib/package.sh
source /payload/files/lib/package.sh

work=/run/can_loop
fail() {
  echo "FAILED: $*"
  for f in "$work"/*.log; do
    [ -f "$f" ] && sed "s|^|$(basename "$f"): |" "$f" | tail -20
  done
  exit 1
}
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
}
trap cleanup EXIT

modprobe -a can can_raw vcan || fail "modprobe can can_raw vcan"
vm_install_package
echo "installed=$(dpkg-query -W -f='${Version} ${Status}' selfsense)"
echo "selfsensed=$(command -v selfsensed)"
mkdir -p "$work/config/plant"
cfg=$work/config/can-sim.yaml
# The packaged example with this test's paths: socket, recordings and telemetry under $work/can-sim.
sed -e "s|/run/selfsensed/|$work/can-sim/|" -e "s|/var/lib/selfsensed/|$work/can-sim/|" \
  /etc/selfsense/examples/can-sim.yaml >"$cfg"
# Software emulation on shared cores is far from real time: a 500 Hz loop and node, a generous
# receive timeout, and a plant sampled at 2 kHz without its 2 kHz mount resonance (a tenth of
# the 20 kHz plant's work per second).
sed -i -e 's/interface: vcan0 /interface: vcanl0 /' -e 's/rx_timeout_ms: 50 /rx_timeout_ms: 500 /' \
  -e 's/rate_hz: 1000 /rate_hz: 500 /' -e 's/frequency_hz: 300.0/frequency_hz: 100.0/g' "$cfg"
rate=500
plant=$work/config/plant/can-vm.yaml
sed -e 's/sample_rate_hz: 20000/sample_rate_hz: 2000/' -e '/^  mechanics:/,/^  [a-z]/s/enabled: true/enabled: false/' \
  /usr/share/selfsense/plant/daemon.yaml >"$plant"
ip link add dev vcanl0 type vcan
ip link set up vcanl0
ip link add dev vcanl1 type vcan
ip link set dev vcanl1 mtu 72
ip link set up vcanl1
selfsense check-config "$cfg" >/dev/null || fail "check-config rejected $cfg"
echo "check_config=ok"

sock=$work/can-sim/control.sock
ctl() { selfsense ctl --socket "$sock" "$@"; }
field() { sed -n "s/.*\"$1\":\([^,}]*\).*/\1/p" <<<"$2" | head -1; }
wait_socket() {
  for _ in $(seq 300); do
    [ -S "$sock" ] && ctl status >/dev/null 2>&1 && return 0
    sleep 0.1
  done
  fail "the daemon's control socket did not come up"
}

candump -L vcanl0,0:0,#FFFFFFFF >"$work/candump.log" &
pids+=($!)
dump=$!
sleep 0.5
selfsense sim-device --can vcanl0 --config "$cfg" --plant "$plant" \
  --rate "$rate" >"$work/sim.log" 2>&1 &
sim=$!
pids+=("$sim")
selfsensed --config "$cfg" >"$work/daemon.log" 2>&1 &
daemon=$!
pids+=("$daemon")
wait_socket
sleep 1
ctl mode position >/dev/null || fail "ctl mode position"
ctl reset >/dev/null || fail "ctl reset"
ctl arm >/dev/null || fail "ctl arm: $(ctl status)"
target=5.0e-4
ctl setpoint "$target" >/dev/null || fail "ctl setpoint"
reached=no
for _ in $(seq 100); do
  sleep 0.2
  status=$(ctl status)
  s_hat=$(field S_hat "$status")
  if awk -v s="$s_hat" -v t="$target" 'BEGIN { d = s - t; if (d < 0) d = -d; exit !(d < 0.05 * t) }'; then
    reached=yes
    break
  fi
done
sleep 1  # settle, then measure
status=$(ctl status)
echo "state_armed=$(field state "$status")"
echo "position_reached=$reached"
echo "s_hat=$(field S_hat "$status") s_true=$(field S "$status") setpoint=$(field setpoint "$status")"
[ "$reached" = yes ] || fail "S_hat did not reach $target: $status"
echo "overruns=$(field overruns "$status") cycles=$(field cycles "$status")"
# The node sends the plant's temperature (25 degC plus its self-heating) in frame 0x103.
temp=$(field temp "$status")
echo "temperature_shown=$(awk -v t="$temp" 'BEGIN { exit !(t + 0 >= 24.9 && t + 0 < 100) }' && echo yes || echo no) ($temp degC)"
before_bad=$(field driver_bad_data "$status")
before_err=$(field driver_errors "$status")

# A frame of the inputs' ID too short for its signals, and a controller error frame.
cansend vcanl0 101#01
cansend vcanl0 20000004#0004000000000000 || fail "cansend could not send an error frame"
sleep 0.5
status=$(ctl status)
after_bad=$(field driver_bad_data "$status")
after_err=$(field driver_errors "$status")
echo "bad_data_counted=$([ "$after_bad" -gt "$before_bad" ] && echo yes || echo no) ($before_bad -> $after_bad)"
echo "error_frame_counted=$([ "$after_err" -gt "$before_err" ] && echo yes || echo no) ($before_err -> $after_err)"
echo "state_after_injection=$(field state "$status")"

# Bus-off (an error frame with CAN_ERR_BUSOFF): counted, reads disconnected until the next input
# frame shows the bus works again (counted as a reconnect); the loop faults and is re-armed.
cansend vcanl0 20000040#0000000000000000 || fail "cansend could not send a bus-off frame"
sleep 0.5
status=$(ctl status)
echo "bus_off_counted=$([ "$(field driver_device_faults "$status")" -ge 1 ] && echo yes || echo no)"
echo "bus_off_recovered=$([ "$(field driver_reconnects "$status")" -ge 1 ] && echo yes || echo no)"
echo "state_after_bus_off=$(field state "$status")"
ctl reset >/dev/null || fail "ctl reset after bus-off"
ctl arm >/dev/null || fail "ctl arm after bus-off"
sleep 0.5
status=$(ctl status)
echo "state_rearmed=$(field state "$status")"
before_timeouts=$(field driver_timeouts "$status")

# The node dies: no inputs, timeout fault, safe output.
kill -TERM "$sim"
sim_rc=0
wait "$sim" || sim_rc=$?
echo "sim_device_exit=$sim_rc"
grep -q '^sim-device: stopped:' "$work/sim.log" && echo "sim_device_summary=yes"
sed -n 's/^sim-device: stopped: /sim_device: /p' "$work/sim.log"
sleep 1
status=$(ctl status)
timeouts=$(field driver_timeouts "$status")
echo "timeouts_counted=$([ "$timeouts" -gt "$before_timeouts" ] && echo yes || echo no) ($before_timeouts -> $timeouts)"
# No temperature frame for temp_timeout_ms (1 s): none is read (counted), not a fault of its own.
echo "temp_timeouts_counted=$([ "$(field temp_timeouts "$status")" -gt 0 ] && echo yes || echo no) (temp $(field temp "$status"))"
echo "state_after_kill=$(field state "$status")"
grep -q '"faults":\[[^]]*"driver_timeout"' <<<"$status" && echo "fault=driver_timeout"
echo "command_after_kill=$(field command "$status")"
kill -TERM "$daemon"
daemon_rc=0
wait "$daemon" || daemon_rc=$?
echo "daemon_exit=$daemon_rc"
sed -n 's/^can: vcanl0: /driver: /p' "$work/daemon.log"
kill "$dump" 2>/dev/null || true
wait "$dump" 2>/dev/null || true
inputs=$(grep -c ' vcanl0 101#' "$work/candump.log" || true)
refs=$(grep -c ' vcanl0 102#' "$work/candump.log" || true)
temps=$(grep -c ' vcanl0 103#' "$work/candump.log" || true)
commands=$(grep -c ' vcanl0 18FF0001#' "$work/candump.log" || true)
echo "candump_frames=$([ "$inputs" -gt 100 ] && [ "$refs" -gt 100 ] && [ "$temps" -gt 100 ] && [ "$commands" -gt 100 ] && echo yes || echo no) (101: $inputs, 102: $refs, 103: $temps, 18FF0001: $commands)"
echo "candump_injected=$(grep -cE ' vcanl0 (101#01|20000004#0004000000000000|20000040#0000000000000000)$' "$work/candump.log")"
# The last command on the bus is the safe output, E = 0.
echo "last_command=$(grep ' vcanl0 18FF0001#' "$work/candump.log" | tail -1 | awk '{ print $3 }')"

# The driver's real-time calls alone (tests/drivers/can_driver_realtime.cpp): 2 s of read() and
# write() at 1 kHz against the node, with every allocation and lock in the process counted.
selfsense sim-device --can vcanl0 --config "$cfg" --plant "$plant" --rate "$rate" \
  --duration 8 >"$work/sim-rt.log" 2>&1 &
sim=$!
pids+=("$sim")
sleep 0.5
# A test program, not in the package: copied in with its libraries (tests/vm/boot.sh).
rt=$(LD_LIBRARY_PATH=/payload/lib /payload/bin/can_driver_realtime vcanl0 "$cfg" 2>&1) || true
echo "$rt"
kill -TERM "$sim" 2>/dev/null || true
wait "$sim" || true

# CAN FD on vcanl1 (MTU 72): the same layout in FD frames.
fd_cfg=$work/config/can-fd.yaml
sed -e 's/interface: vcanl0 /interface: vcanl1 /' -e 's/^  fd: false /  fd: true /' \
  -e 's|can-sim/|can-fd/|' "$cfg" >"$fd_cfg"
sock=$work/can-fd/control.sock
candump -L vcanl1 >"$work/candump-fd.log" &
dump=$!
pids+=("$dump")
sleep 0.5
selfsense sim-device --can vcanl1 --config "$fd_cfg" --plant "$plant" \
  --rate "$rate" --duration 6 >"$work/sim-fd.log" 2>&1 &
sim=$!
pids+=("$sim")
selfsensed --config "$fd_cfg" >"$work/daemon-fd.log" 2>&1 &
daemon=$!
pids+=("$daemon")
wait_socket
sleep 1
decoded=no
for _ in $(seq 20); do
  status=$(ctl status)
  e=$(field E "$status")
  if [ -n "$e" ] && [ "$e" != null ] && [ "$(field driver_reads "$status")" -gt 100 ]; then
    decoded=yes
    break
  fi
  sleep 0.2
done
echo "fd_inputs_decoded=$decoded (E=$(field E "$status") D=$(field D "$status") S=$(field S "$status"))"
kill -TERM "$daemon"
wait "$daemon" || true
wait "$sim" || true
kill "$dump" 2>/dev/null || true
wait "$dump" 2>/dev/null || true
fd_inputs=$(grep -c ' vcanl1 101##' "$work/candump-fd.log" || true)
fd_commands=$(grep -c ' vcanl1 18FF0001##' "$work/candump-fd.log" || true)
echo "fd_frames=$([ "$fd_inputs" -gt 100 ] && [ "$fd_commands" -gt 100 ] && echo yes || echo no) (101: $fd_inputs, 18FF0001: $fd_commands)"
sed -n 's/^can: vcanl1: /fd_driver: /p' "$work/daemon-fd.log"

# Measured only (not asserted): the loop rate the VM sustains over vcan, node and daemon both at
# the rate, 3 s each, disarmed (read and write every cycle all the same).
for r in 1000 2000; do
  sweep_cfg=$work/config/can-sweep-$r.yaml
  sed -e "s/rate_hz: 500 /rate_hz: $r /" -e "s|can-sim/|can-sweep-$r/|" "$cfg" >"$sweep_cfg"
  sock=$work/can-sweep-$r/control.sock
  selfsense sim-device --can vcanl0 --config "$sweep_cfg" --plant "$plant" --rate "$r" \
    --duration 5 >"$work/sim-sweep.log" 2>&1 &
  sim=$!
  selfsensed --config "$sweep_cfg" >"$work/daemon-sweep.log" 2>&1 &
  daemon=$!
  wait_socket
  sleep 1
  t1=$(date +%s.%N)
  c1=$(field cycles "$(ctl status)")
  sleep 2
  t2=$(date +%s.%N)
  status=$(ctl status)
  c2=$(field cycles "$status")
  kill -TERM "$daemon"
  wait "$daemon" || true
  wait "$sim" || true
  echo "sweep_rate=$r achieved_hz=$(awk -v a="$c1" -v b="$c2" -v s="$t1" -v e="$t2" 'BEGIN { printf "%.0f", (b - a) / (e - s) }') overruns=$(field overruns "$status") missed=$(field missed_periods "$status") timeouts=$(field driver_timeouts "$status") $(sed -n 's/^sim-device: stopped: \(ticks=[0-9]* late=[0-9]*\).*/node_\1/p' "$work/sim-sweep.log") $(sed -n 's/^can: vcanl0: \(rx_to_tx_us p50=[0-9]*\).*\(read_to_write_us p50=[0-9.]*\).*/\1 \2/p' "$work/daemon-sweep.log")"
done
