# Sourced by the host side of the VM tests: the boot (boot.sh) runs every payload test in one
# VM and leaves its console in OUT_DIR; each test then checks its own results there.
# shellcheck shell=bash

vm_repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
vm_skip=77
# The VM's architecture, as scripts/vm/ reads it (CTest sets it for the arm64 VM's tests).
# shellcheck disable=SC2034 # read by the scripts that source this one
vm_arch=${SELFSENSE_VM_ARCH:-amd64}

# Skips (CTest SKIP_RETURN_CODE) when the image is not built, as on a machine that never ran
# scripts/vm/image.sh; CI builds it first (scripts/setup.sh run_vm_tests).
vm_require_image() {
  if ! "$vm_repo/scripts/vm/image.sh" --check >/dev/null; then
    echo "SKIP: no cached VM image; build it with scripts/vm/image.sh (as root)"
    exit "$vm_skip"
  fi
}

# vm_check_test OUT_DIR NAME MARKER...: shows NAME's lines from the boot, then asserts that it
# passed inside the VM and printed each MARKER (a whole line after its prefix, as a regex).
vm_check_test() {
  local out=$1 name=$2 marker missing=0
  shift 2
  vm_require_image
  [ -f "$out/results.txt" ] || { echo "FAIL: $out/results.txt missing: did vm.boot run?"; exit 1; }
  grep -E "^SELFSENSE-VM: (TEST $name |\[$name\] )" "$out/results.txt" || true
  if ! grep -qE "^SELFSENSE-VM: TEST $name (PASS|FAIL) " "$out/results.txt"; then
    echo "FAIL: $name did not run in the VM (status $(cat "$out/status" 2>/dev/null || echo ?)); console: $out/console.log"
    exit 1
  fi
  for marker in "$@"; do
    if ! grep -qE "^SELFSENSE-VM: \[$name\] $marker\$" "$out/results.txt"; then
      echo "FAIL: $name: no line matching '$marker'"
      missing=1
    fi
  done
  if ! grep -qE "^SELFSENSE-VM: TEST $name PASS " "$out/results.txt"; then
    echo "FAIL: $name failed inside the VM"
    exit 1
  fi
  [ "$missing" -eq 0 ] || exit 1
  echo "PASS: $name"
}
