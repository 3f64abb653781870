#!/usr/bin/env bash
# The layering check must fail on each kind of violation and pass on a clean tree.
set -euo pipefail
check=${1:?usage: self_test.sh CHECK_SCRIPT}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/src/models" "$tmp/include/selfsense/operators" "$tmp/src/cli"
echo '#include "selfsense/operators/play.hpp"' >"$tmp/src/models/ok.cpp"
bash "$check" "$tmp" >/dev/null || { echo "FAIL: a clean tree was rejected"; exit 1; }

expect_failure() {
  local what=$1 pattern=$2
  if out=$(bash "$check" "$tmp" 2>&1); then
    echo "FAIL: $what passed the check"
    exit 1
  fi
  grep -q "$pattern" <<<"$out" || { echo "FAIL: $what: no line matching '$pattern' in: $out"; exit 1; }
  echo "ok: $what rejected"
}

echo '#include "selfsense/identification/operator_fit.hpp"' >"$tmp/src/models/fit.cpp"
expect_failure "models including identification" "src/models/fit.cpp:1: models must not include selfsense/identification"
rm "$tmp/src/models/fit.cpp"

printf '#pragma once\n#include <fstream>\n' >"$tmp/include/selfsense/operators/io.hpp"
expect_failure "math including <fstream>" "include/selfsense/operators/io.hpp:2: pure math (operators) must not include <fstream>"
rm "$tmp/include/selfsense/operators/io.hpp"

mkdir -p "$tmp/drivers/can" "$tmp/src/daemon"
echo '#include "selfsense/drivers/spi/spi_bus.hpp"' >"$tmp/drivers/can/can_driver.cpp"
expect_failure "a driver including another driver" "drivers/can/can_driver.cpp:1: drivers/can must not include selfsense/drivers/spi"
rm "$tmp/drivers/can/can_driver.cpp"

echo '#include "selfsense/drivers/can/can_driver.hpp"' >"$tmp/src/daemon/daemon.cpp"
expect_failure "the daemon including a driver" "src/daemon/daemon.cpp:1: daemon must not include selfsense/drivers/can"
rm "$tmp/src/daemon/daemon.cpp"

echo '#include "selfsense/plotting/svg.hpp"' >"$tmp/src/cli/plot.cpp"
expect_failure "the tool including an unknown library" "src/cli/plot.cpp:1: cli must not include selfsense/plotting"
rm "$tmp/src/cli/plot.cpp"

mkdir -p "$tmp/drivers/ethercat"
expect_failure "an unknown driver folder" "drivers/ethercat: library folder not in"
rmdir "$tmp/drivers/ethercat"

mkdir -p "$tmp/src/newlib"
expect_failure "an unknown library folder" "src/newlib: library folder not in"
echo "layering self-test: ok"
