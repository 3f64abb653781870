#!/usr/bin/env bash
# Entry point of a multi-test payload (copied to /payload/run.sh by run_tests.sh): runs every
# /payload/tests/*.sh in turn, one VM boot for all of them, and reports each on its own:
#   SELFSENSE-VM: TEST name START
#   SELFSENSE-VM: [name] <each line the test prints>
#   SELFSENSE-VM: TEST name PASS|FAIL rc=N 1.23s
# Exits with the number of failed tests (at most 100).
set -euo pipefail

export PATH=/payload/bin:$PATH
export LD_LIBRARY_PATH=/payload/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
# Each test gets its own limit, well inside run.sh's limit for the whole boot.
# package_systemd took 83-111 s at load average 5-6 on 2 cores (its upgrade 38-56 s), 2026-11-27.
per_test_timeout=180
# The arm64 VM emulates another instruction set: its package_systemd (install, start, arm, record,
# stop, remove, purge, no upgrade) took 161 s at load average 7 on 2 cores, 2026-11-27.
[ "$(uname -m)" != aarch64 ] || per_test_timeout=360

now() { cut -d' ' -f1 /proc/uptime; }

failed=0
for test in /payload/tests/*.sh; do
  [ -f "$test" ] || continue
  name=$(basename "$test" .sh)
  echo "SELFSENSE-VM: TEST $name START"
  begin=$(now)
  # A test that hangs is stopped and fails instead of using up the whole VM's time.
  set +e
  timeout "$per_test_timeout" bash "$test" 2>&1 | sed -u "s/^/SELFSENSE-VM: [$name] /"
  rc=${PIPESTATUS[0]}
  set -e
  seconds=$(awk -v a="$begin" -v b="$(now)" 'BEGIN { printf "%.2f", b - a }')
  if [ "$rc" -eq 0 ]; then
    echo "SELFSENSE-VM: TEST $name PASS rc=0 ${seconds}s"
  else
    echo "SELFSENSE-VM: TEST $name FAIL rc=$rc ${seconds}s"
    failed=$((failed + 1))
  fi
done
exit $((failed > 100 ? 100 : failed))
