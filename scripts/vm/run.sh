#!/usr/bin/env bash
# Boots the cached VM image (scripts/vm/image.sh) under qemu's software emulation with
# PAYLOAD_DIR as a second disk, and exits with the status of PAYLOAD_DIR/run.sh inside.
#
#   scripts/vm/run.sh PAYLOAD_DIR [TIMEOUT_S]
#
# PAYLOAD_DIR/run.sh runs as root under systemd once the system is up, with /payload as its
# working directory and its output on the serial console. Lines it prints starting with
# "SELFSENSE-VM:" are the results, shown here; the whole console goes to $SELFSENSE_VM_LOG
# (default: a fresh file under /tmp, named at the end). When $SELFSENSE_VM_OUT is set, what the
# payload left under /payload/out is copied back to $SELFSENSE_VM_OUT/out.
#
# SELFSENSE_VM_ARCH=arm64 boots the arm64 image under qemu-system-aarch64 (the virt board).
#
# Exit status: the payload's; 124 when the VM ran out of time (TIMEOUT_S, default 300);
# 125 when it stopped without reporting one (kernel panic, boot failure); 77 when the image
# has not been built.
set -euo pipefail
# shellcheck source-path=SCRIPTDIR source=common.sh
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

[ $# -eq 1 ] || [ $# -eq 2 ] || vm_die "usage: scripts/vm/run.sh PAYLOAD_DIR [TIMEOUT_S]"
payload=$1
timeout_s=${2:-300}
[ -f "$payload/run.sh" ] || vm_die "$payload/run.sh: no such file (the payload's entry point)"
[[ $timeout_s =~ ^[1-9][0-9]*$ ]] || vm_die "TIMEOUT_S must be a positive number of seconds, not '$timeout_s'"
if ! image=$("$vm_scripts/image.sh" --check); then
  vm_say "no cached VM image for key $(vm_key) under $vm_cache_root; build it: scripts/vm/image.sh"
  exit 77
fi
# -cpu max lets host-built programs use the instructions the host has. The arm64 guest is the
# virt board (no firmware needed with -kernel) with a Cortex-A72, as on a Raspberry Pi 4/CM4:
# the arm64 programs are built for plain armv8-a, and qemu emulates it faster than -cpu max.
if [ "$vm_arch" = arm64 ]; then
  qemu=(qemu-system-aarch64 -M virt -cpu cortex-a72)
else
  qemu=(qemu-system-x86_64 -cpu max)
fi
command -v "${qemu[0]}" >/dev/null || vm_die "${qemu[0]} missing; run scripts/vm/image.sh (as root)"

work=$(mktemp -d /tmp/selfsense-vm.XXXXXX)
log=${SELFSENSE_VM_LOG:-$work/console.log}
# The scratch payload disk goes with the run; the console log stays unless it lives in $work.
# shellcheck disable=SC2317 # called by the EXIT trap
cleanup() {
  rm -f "$work/payload.img"
  [ "$log" = "$work/console.log" ] || rm -rf "$work"
}
trap cleanup EXIT

# Room for what the payload brings and what it writes under out/.
size_mib=$(($(du -sm "$payload" | cut -f1) * 2 + 64))
mke2fs -q -t ext4 -L payload -d "$payload" "$work/payload.img" "${size_mib}M" >/dev/null

# quiet and loglevel=3 keep the console to the payload's lines and real errors; panic=-1 with
# -no-reboot turns a kernel panic into qemu exiting at once instead of a hang.
append="root=/dev/vda rw console=$(vm_console) quiet loglevel=3 panic=-1 systemd.show_status=false"
append+=" ${SELFSENSE_VM_APPEND:-}"

vm_say "run: booting $image with payload $payload (timeout ${timeout_s} s)"
start=$SECONDS
status=0
# snapshot=on keeps the cached root unchanged (writes go to a temporary file). -nodefaults: no
# network, VGA, floppy or CD-ROM to probe; the payload brings everything it needs.
timeout --kill-after=10 "$timeout_s" "${qemu[@]}" \
  -m 1024 -smp 2 -nographic -no-reboot -nodefaults -serial stdio \
  -kernel "$image/vmlinuz" -initrd "$image/initrd.img" -append "$append" \
  -drive "file=$image/root.img,format=raw,if=virtio,snapshot=on" \
  -drive "file=$work/payload.img,format=raw,if=virtio" \
  </dev/null >"$log" 2>&1 || status=$?
elapsed=$((SECONDS - start))

# The serial console ends lines with CR LF, and terminal resets may precede a marker on its line.
results=$(tr -d '\r' <"$log" | grep -ao 'SELFSENSE-VM: .*' || true)
[ -z "$results" ] || printf '%s\n' "$results"

if [ -n "${SELFSENSE_VM_OUT:-}" ]; then
  mkdir -p "$SELFSENSE_VM_OUT"
  rm -rf "${SELFSENSE_VM_OUT:?}/out"
  # debugfs reads the ext4 image without mounting it; it exits 0 even when /out is missing.
  debugfs -R "rdump /out $SELFSENSE_VM_OUT" "$work/payload.img" >/dev/null 2>&1 || true
  [ -d "$SELFSENSE_VM_OUT/out" ] || vm_say "run: the payload left no /payload/out"
fi

exit_line=$(printf '%s\n' "$results" | grep -E '^SELFSENSE-VM: EXIT [0-9]+$' | tail -1 || true)
if [ "$status" -eq 124 ] || [ "$status" -eq 137 ]; then
  vm_say "run: timed out after ${timeout_s} s; console: $log"
  tail -20 "$log" >&2
  exit 124
fi
if [ -z "$exit_line" ]; then
  vm_say "run: the VM stopped (qemu status $status) without reporting the payload's exit status; console: $log"
  grep -a -i -E 'panic|error|fail' "$log" | head -20 >&2 || tail -20 "$log" >&2
  exit 125
fi
rc=${exit_line##* }
vm_say "run: payload exit status $rc after ${elapsed} s in total; console: $log"
exit "$rc"
