#!/usr/bin/env bash
# Host side of payload/program_smoke.sh: the host-built selfsense tool ran inside the VM with
# the libraries add_program.sh copied, and printed exactly what it prints on the host.
#   tests/vm/program_smoke.sh OUT_DIR SELFSENSE   (after tests/vm/boot.sh OUT_DIR SELFSENSE)
set -euo pipefail
# shellcheck source-path=SCRIPTDIR source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"

[ $# -eq 2 ] || { echo "usage: tests/vm/program_smoke.sh OUT_DIR SELFSENSE" >&2; exit 2; }
out=$1
host_demo=$("$2" demo)
vm_check_test "$out" program_smoke 'libs_from_payload=yes' "demo_lines=$(wc -l <<<"$host_demo")"

vm_demo=$(sed -n 's/^SELFSENSE-VM: \[program_smoke\] demo: \{0,1\}//p' "$out/results.txt")
if [ "$vm_demo" != "$host_demo" ]; then
  echo "FAIL: selfsense demo printed something else in the VM than on the host:"
  diff <(echo "$host_demo") <(echo "$vm_demo") || true
  exit 1
fi
echo "PASS: selfsense demo prints the same in the VM as on the host"
