#!/usr/bin/env bash
# CTest fixture vm.boot: one VM boot that runs every tests/vm/payload/*.sh. It fails only when
# the VM itself did not report (timeout, panic, no payload); each test's own result is checked
# by its CTest test (systemd_smoke.sh, can_smoke.sh, ...), so one failure does not hide the
# others. The PROGRAMs (host-built, e.g. the selfsense tool) go in with their libraries.
#   tests/vm/boot.sh OUT_DIR [PROGRAM...]
set -euo pipefail
# shellcheck source-path=SCRIPTDIR source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"

[ $# -ge 1 ] || { echo "usage: tests/vm/boot.sh OUT_DIR [PROGRAM...]" >&2; exit 2; }
out=$1
shift
vm_require_image
args=(--timeout 420)
for program in "$@"; do
  args+=(--program "$program")
done
status=0
"$vm_repo/scripts/vm/run_tests.sh" "$out" "${args[@]}" "$vm_repo"/tests/vm/payload/*.sh || status=$?
case "$status" in
  77) echo "SKIP: no cached VM image"; exit "$vm_skip" ;;
  124 | 125) echo "FAIL: the VM did not report (status $status); console: $out/console.log"; exit 1 ;;
  0) echo "vm.boot: every payload test passed" ;;
  *) echo "vm.boot: the VM ran; $status payload test(s) failed (see their own results)" ;;
esac
