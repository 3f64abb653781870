#!/usr/bin/env bash
# Runs test scripts inside one VM boot: assembles a payload of scripts/vm/payload_tests.sh and
# the given scripts (and programs, with their libraries), boots it with run.sh, and leaves the
# console log and the result lines in OUT_DIR.
#
#   scripts/vm/run_tests.sh OUT_DIR [--program BINARY]... [--timeout S] TEST.sh...
#
# OUT_DIR/console.log   the whole serial console
# OUT_DIR/results.txt   the SELFSENSE-VM: lines (per test: START, its output, PASS or FAIL)
# OUT_DIR/status        run.sh's exit status (the number of failed tests, or 124/125/77)
# OUT_DIR/out/          what the tests wrote under /payload/out
# Exit status: run.sh's.
set -euo pipefail
# shellcheck source-path=SCRIPTDIR source=common.sh
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

usage="usage: scripts/vm/run_tests.sh OUT_DIR [--program BINARY]... [--timeout S] TEST.sh..."
[ $# -ge 2 ] || vm_die "$usage"
out=$1
shift
programs=()
timeout_s=300
tests=()
while [ $# -gt 0 ]; do
  case "$1" in
    --program) programs+=("${2:?$usage}"); shift 2 ;;
    --timeout) timeout_s=${2:?$usage}; shift 2 ;;
    -*) vm_die "unknown option $1; $usage" ;;
    *) tests+=("$1"); shift ;;
  esac
done
[ ${#tests[@]} -gt 0 ] || vm_die "no test scripts given; $usage"

rm -rf "$out"
mkdir -p "$out/payload/tests" "$out/payload/out"
install -m 0755 "$vm_scripts/payload_tests.sh" "$out/payload/run.sh"
for test in "${tests[@]}"; do
  [ -f "$test" ] || vm_die "$test: no such test script"
  install -m 0755 "$test" "$out/payload/tests/"
done
[ ${#programs[@]} -eq 0 ] || "$vm_scripts/add_program.sh" "$out/payload" "${programs[@]}"

status=0
SELFSENSE_VM_LOG="$out/console.log" SELFSENSE_VM_OUT="$out" \
  "$vm_scripts/run.sh" "$out/payload" "$timeout_s" >"$out/results.txt" || status=$?
echo "$status" >"$out/status"
cat "$out/results.txt"
exit "$status"
