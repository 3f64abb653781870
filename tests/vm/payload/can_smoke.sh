#!/usr/bin/env bash
# Inside the VM, with the kernel's SocketCAN stack: a vcan interface, Debian's can-utils
# sending a standard, an extended and a CAN FD frame, candump receiving them. Also checks that
# a CAN FD frame is refused while the interface's MTU is classic CAN (so the FD pass means
# something). Prints "name=value" lines that tests/vm/can_smoke.sh checks.
set -euo pipefail

fail() {
  echo "FAILED: $*"
  exit 1
}

modprobe -a can can_raw vcan || fail "modprobe can can_raw vcan"
echo "modules=$(lsmod | awk '$1 ~ /^(can|can_raw|vcan)$/ { print $1 }' | sort | tr '\n' ' ')"
ip link add dev vcan0 type vcan
ip link set dev vcan0 mtu 16
ip link set up vcan0
if cansend vcan0 '456##1.00112233' 2>/dev/null; then
  fail "a CAN FD frame was sent on an interface with the classic MTU of 16"
fi
echo "fd_refused_at_mtu16=yes"
ip link set down vcan0
ip link set dev vcan0 mtu 72
ip link set up vcan0
echo "link=$(ip -details link show vcan0 | tr -s ' \n' ' ')"

log=/run/candump.log
candump -L vcan0 >"$log" &
dump=$!
# candump binds its socket right after start; frames sent before that would be missed.
sleep 1
cansend vcan0 123#DEADBEEF
cansend vcan0 12345678#0011223344556677
cansend vcan0 '456##1.00112233445566778899AABBCCDDEEFF'
sleep 1
kill "$dump"
wait "$dump" 2>/dev/null || true
sed 's/^/candump: /' "$log"

# candump -L: "(seconds) vcan0 ID#DATA", FD frames "ID##<flags nibble>DATA"; the kernel may add
# flags on reception, so the FD pattern leaves the nibble open.
expect() {
  if grep -qE " vcan0 $2\$" "$log"; then
    echo "seen_$1=yes"
  else
    fail "candump did not see the $1 frame $2"
  fi
}
expect standard '123#DEADBEEF'
expect extended '12345678#0011223344556677'
expect fd '456##[0-9A-F]00112233445566778899AABBCCDDEEFF'
frames=$(wc -l <"$log")
echo "frames=$frames"
[ "$frames" -eq 3 ] || fail "candump saw $frames frames, expected 3"
