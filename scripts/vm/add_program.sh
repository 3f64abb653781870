#!/usr/bin/env bash
# Copies host-built programs into a VM payload with the shared libraries `ldd` lists for them,
# for libraries the image may lack. Inside the VM they are /payload/bin/NAME and
# /payload/lib/; scripts/vm/payload_tests.sh puts both on PATH and LD_LIBRARY_PATH.
#
#   scripts/vm/add_program.sh PAYLOAD_DIR BINARY...
#
# glibc's own libraries are left out on purpose: they must match the image's dynamic loader,
# and the image has Debian 12's glibc, which host-built Debian 12 programs run on.
set -euo pipefail
# shellcheck source-path=SCRIPTDIR source=common.sh
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

[ $# -ge 2 ] || vm_die "usage: scripts/vm/add_program.sh PAYLOAD_DIR BINARY..."
payload=$1
shift
mkdir -p "$payload/bin" "$payload/lib"

glibc='^(ld-linux.*|libc|libm|libdl|libpthread|librt|libresolv|libutil|libanl|libmvec)\.so'
for binary in "$@"; do
  if [ ! -f "$binary" ] || [ ! -x "$binary" ]; then
    vm_die "$binary: not an executable file"
  fi
  ldd_out=$(ldd "$binary" 2>&1) || vm_die "$binary: ldd failed: $ldd_out"
  if grep -q 'not found' <<<"$ldd_out"; then
    vm_die "$binary: libraries missing on this host: $(grep 'not found' <<<"$ldd_out" | tr -s ' \t' ' ')"
  fi
  install -m 0755 "$binary" "$payload/bin/"
  copied=0
  # Lines look like "libfoo.so.1 => /usr/lib/x86_64-linux-gnu/libfoo.so.1 (0x...)".
  while read -r name _ path _; do
    if [ -z "${path:-}" ] || [ ! -f "$path" ] || [[ $name =~ $glibc ]]; then
      continue
    fi
    cp -L "$path" "$payload/lib/$name"
    copied=$((copied + 1))
  done < <(grep '=> /' <<<"$ldd_out")
  vm_say "add_program: $(basename "$binary") and $copied libraries into $payload"
done
