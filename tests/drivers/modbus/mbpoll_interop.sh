#!/usr/bin/env bash
# Interoperability: Debian's mbpoll (an independent Modbus master) reads the sim-device's input
# registers, writes its command register and reads it back, and gets the exception response for
# an unmapped register. Skips (exit 77, CTest shows "Skipped") only when mbpoll is not installed;
# scripts/setup.sh installs it.
#   mbpoll_interop.sh SELFSENSE_CLI SOURCE_DIR
set -euo pipefail
cli=${1:?usage: mbpoll_interop.sh SELFSENSE_CLI SOURCE_DIR}
root=${2:?usage: mbpoll_interop.sh SELFSENSE_CLI SOURCE_DIR}
if ! command -v mbpoll >/dev/null; then
  echo "SKIP: mbpoll is not installed (apt-get install mbpoll; scripts/setup.sh does)" >&2
  exit 77
fi
out=$(mktemp -d)
fail() { echo "FAIL: $*" >&2; exit 1; }
"$cli" sim-device --modbus-tcp 127.0.0.1:0 --plant "$root/config/plant/daemon.yaml" --rate 1000 >"$out/device.log" 2>&1 &
pid=$!
trap 'kill -KILL $pid 2>/dev/null || true; rm -rf "$out"' EXIT
for _ in $(seq 100); do grep -qs 'modbus-tcp on' "$out/device.log" && break; sleep 0.05; done
port=$(sed -n 's/.*modbus-tcp on 127.0.0.1:\([0-9]*\),.*/\1/p' "$out/device.log")
[ -n "$port" ] || fail "sim-device did not start: $(cat "$out/device.log")"
# -0: addresses from 0 as in the register map; -B: high word first; -1: one poll.
# mb OPTIONS... [-- VALUES...]: the values to write follow the host.
mb() {
  local opts=()
  while [ $# -gt 0 ] && [ "$1" != -- ]; do opts+=("$1"); shift; done
  [ $# -gt 0 ] && shift
  mbpoll -m tcp -p "$port" -a 1 -0 -1 -B "${opts[@]}" 127.0.0.1 "$@"
}
value() { sed -n "s/^\[$1\]:[[:space:]]*\([-0-9.e+]*\).*/\1/p"; }

mb -t 3:float -r 0 -c 4 >"$out/inputs.txt" || fail "mbpoll could not read the inputs: $(cat "$out/inputs.txt")"
for reg in 0 2 4 6; do
  v=$(value $reg <"$out/inputs.txt")
  [ -n "$v" ] || fail "no value for input register $reg in: $(cat "$out/inputs.txt")"
done
echo "ok: mbpoll read E, D, S, T: $(value 0 <"$out/inputs.txt") $(value 2 <"$out/inputs.txt") $(value 4 <"$out/inputs.txt") $(value 6 <"$out/inputs.txt")"

mb -t 4:float -r 0 -- 1500000 >"$out/write.txt" || fail "mbpoll could not write the command: $(cat "$out/write.txt")"
mb -t 4:float -r 0 -c 1 >"$out/command.txt"
c=$(value 0 <"$out/command.txt")
awk -v c="$c" 'BEGIN { exit !(c == 1500000) }' || fail "command register reads back '$c', wrote 1500000"
sleep 0.5
mb -t 3:float -r 0 -c 1 >"$out/e.txt"
e=$(value 0 <"$out/e.txt")
awk -v e="$e" 'BEGIN { exit !(e > 1.45e6 && e < 1.55e6) }' || fail "measured E $e does not follow the command 1.5e6"
echo "ok: mbpoll wrote the command 1.5e6 V/m; the device's measured E is $e"

if mb -t 3 -r 40 -c 1 >"$out/unmapped.txt" 2>&1; then fail "an unmapped register was answered"; fi
grep -qi 'illegal data address' "$out/unmapped.txt" || fail "no exception response: $(cat "$out/unmapped.txt")"
echo "ok: unmapped register 40: illegal data address"

kill -TERM "$pid"
rc=0
wait "$pid" || rc=$?
[ "$rc" -eq 0 ] || fail "sim-device exited with $rc after SIGTERM"
echo "mbpoll interoperability: ok"
