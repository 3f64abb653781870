#!/usr/bin/env bash
# Inside the VM: a program built on the host and copied in by scripts/vm/add_program.sh (here
# the selfsense tool) runs with the libraries it brought, from /payload/bin and /payload/lib.
# Prints its `selfsense demo` output for tests/vm/program_smoke.sh to compare with the host's.
set -euo pipefail

fail() {
  echo "FAILED: $*"
  exit 1
}

program=/payload/bin/selfsense
[ -x "$program" ] || fail "$program missing (tests/vm/boot.sh copies it in with --program)"
libs=$(ldd "$program")
awk '{ print "ldd: " $0 }' <<<"$libs"
if grep -q 'not found' <<<"$libs"; then
  fail "unresolved libraries"
fi
if grep -qE '=> /payload/lib/' <<<"$libs"; then
  echo "libs_from_payload=yes"
else
  fail "no library resolved from /payload/lib (LD_LIBRARY_PATH not set?)"
fi
out=$(selfsense demo) || fail "selfsense demo exited with $?"
awk '{ print "demo: " $0 }' <<<"$out"
echo "demo_lines=$(wc -l <<<"$out")"
